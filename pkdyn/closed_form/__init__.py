"""Closed-form geometric models of library robots, vectorised over poses (numpy)."""

from pkdyn.closed_form import delta, gough_stewart, planar_3rrr

__all__ = ["delta", "gough_stewart", "planar_3rrr"]
