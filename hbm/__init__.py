"""Multi-harmonic balance (AFT) solver for structures damped by dry friction."""
