"""Reporting: the verdict rule (``verdicts``), numbers with their intervals (``reported``), text and tables
(``text``), and each chapter's typed numbers (``report.<chapter>``), which the summary reads instead of the
chapters."""
