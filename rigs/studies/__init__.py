"""Parameter studies of the rigs (scripts with importable functions)."""
