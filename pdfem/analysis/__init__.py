"""Analysis of a shock run: compaction front, jump conditions, Hugoniot, figures, summary."""

from pdfem.analysis.summary import analyse

__all__ = ["analyse"]
