"""Optical transfer functions, one module per mechanism."""
