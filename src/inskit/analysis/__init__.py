"""Error analysis: navigation errors against truth (:mod:`.errors`), Allan
variance of static logs (:mod:`.allan`), and a filter's consistency axis by
axis (:mod:`.consistency`)."""

from .consistency import axis_innovation_rms, axis_scale_step, horizontal_vertical
from .errors import (PER_EPOCH_COLUMNS, ConstantOffset, NavError, constant_offset, nav_error, per_epoch_columns,
                     truth_coverage, truth_covers, truth_gaps,
                     line_breaks, plot_errors, remove_offset, restrict, summarize)

__all__ = ["axis_innovation_rms", "axis_scale_step", "horizontal_vertical", "PER_EPOCH_COLUMNS", "ConstantOffset", "NavError", "constant_offset", "nav_error", "per_epoch_columns",
           "truth_coverage", "truth_covers", "truth_gaps",
           "line_breaks", "plot_errors", "remove_offset", "restrict", "summarize"]
