"""What is computed from the balance: the FRF and sweeps, stability, jumps, error estimates."""
