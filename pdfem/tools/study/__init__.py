"""Studies of the solver itself, run by ``python -m pdfem study <name>``.

- :mod:`pdfem.tools.study.accuracy`: what accuracy costs in time on a shock scene (levels, rules,
  time-step safety, contact stiffness against the finest run; Pareto front, a 5 % choice);
- :mod:`pdfem.tools.study.convergence`: the observed order of the element on a standing elastic
  wave with a closed-form solution.
"""
