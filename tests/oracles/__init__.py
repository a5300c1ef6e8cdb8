"""Independent NumPy versions of what the package computes once, in JAX (issue 32: one engine).

They are oracles for the tests only: the package never imports them."""
