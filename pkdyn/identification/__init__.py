"""Dynamic identification of closed-loop robots (placeholder docstring, completed below)."""
