"""Error analysis: navigation errors against truth (:mod:`.errors`) and Allan
variance of static logs (:mod:`.allan`)."""

from .errors import NavError, nav_error, plot_errors, summarize

__all__ = ["NavError", "nav_error", "plot_errors", "summarize"]
