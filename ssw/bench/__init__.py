"""Benchmarks behind ``ssw bench``; one module per kind, each with ``register``."""
