"""Builders that turn a few readable parameters into a linear model (``BUILDERS[key](**keys)``)."""
from hbm.builders.beam import build_beam_model

BUILDERS = {"beam": build_beam_model}

__all__ = ["BUILDERS", "build_beam_model"]
