"""blockid: identification of block-oriented nonlinear models."""
