"""Figures (matplotlib) and the design report."""
