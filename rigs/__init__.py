"""Seed systems and user cases as data (TOML), and the builders that read them."""
