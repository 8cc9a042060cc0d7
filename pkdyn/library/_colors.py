"""The colours of the library robots' links (RGBA, 0-1): base and frame, driven links, rods."""

__all__ = ["BLUE", "GREY", "ORANGE"]

GREY = (0.6, 0.6, 0.65, 1.0)
"""Bases, platforms and other fixed or carried bodies."""
BLUE = (0.2, 0.4, 0.8, 1.0)
"""Driven links (arms, cranks, proximal links)."""
ORANGE = (0.9, 0.5, 0.1, 1.0)
"""Rods, bars and distal links."""
