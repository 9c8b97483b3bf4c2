"""Perception (Sec. 5.4.3-5.4.4)."""
