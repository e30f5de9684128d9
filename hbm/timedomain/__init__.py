"""The time-domain reference: implicit integration, shooting and Floquet multipliers."""
