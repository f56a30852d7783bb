"""Analysis of a shock run: compaction front, jump conditions, Hugoniot, figures, summary."""

from pdfem.tools.analysis.summary import analyse

__all__ = ["analyse"]
