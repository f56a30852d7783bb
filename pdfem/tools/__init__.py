"""Tools built on the solver, not part of it; the command line runs them.

- :mod:`pdfem.tools.analysis`: shock analysis and hot-spot census of a run file, figures,
  summary (``python -m pdfem analyse``, ``hotspots``; run at the end of every shock run);
- :mod:`pdfem.tools.bench`: the benchmarks, their C yardsticks and the LAMMPS deck
  (``python -m pdfem bench ...``);
- :mod:`pdfem.tools.study`: studies of the solver (``python -m pdfem study ...``) and the
  sweep's scenes (``python -m pdfem sweep``).

The solver never imports from here: only :mod:`pdfem.cli` and the tools themselves do.
"""
