"""Shipped design presets (TOML files)."""
