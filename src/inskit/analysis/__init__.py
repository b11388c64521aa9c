"""Error analysis: navigation errors against truth (:mod:`.errors`) and Allan
variance of static logs (:mod:`.allan`)."""

from .errors import (PER_EPOCH_COLUMNS, ConstantOffset, NavError, constant_offset, nav_error, per_epoch_columns,
                     truth_coverage, truth_covers, truth_gaps,
                     line_breaks, plot_errors, remove_offset, restrict, summarize)

__all__ = ["PER_EPOCH_COLUMNS", "ConstantOffset", "NavError", "constant_offset", "nav_error", "per_epoch_columns",
           "truth_coverage", "truth_covers", "truth_gaps",
           "line_breaks", "plot_errors", "remove_offset", "restrict", "summarize"]
