"""The reproduction report: Table 1, the paper's claims with verdicts, and the figures, from the sweep's tables.

- :mod:`dgmm.report.tables`   tables from the tidy CSVs (likelihood means, Fig 2 bars, registration, Table 1);
- :mod:`dgmm.report.claims`   each claim of the paper checked by an explicit rule;
- :mod:`dgmm.report.figures`  one function per figure (matplotlib, Agg canvas, no pyplot);
- :mod:`dgmm.report.document` Markdown and self-contained HTML from one list of blocks;
- :mod:`dgmm.report.build`    the table of figures and :func:`build_report`.
"""
from dgmm.report.build import FIGURES, INPUTS, build_report, figure_names

__all__ = ["FIGURES", "INPUTS", "build_report", "figure_names"]
