"""Seed systems and user cases as data (TOML), the scripts that make their model files, and their studies."""
