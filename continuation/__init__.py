"""Pseudo-arclength continuation on any callable ``x -> (R, dR/dx)``; knows nothing of HBM."""
