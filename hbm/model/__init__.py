"""The linear structure: matrices, modal reduction with residual flexibility, model files."""
