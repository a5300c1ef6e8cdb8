"""The names every layer shares, importable without JAX (the command line's parser builds its
choices from them before any JAX import): the defect locations, in the order of the fault classes.

``bearingsim.defect.LOCATIONS`` is this tuple; the data set classes are ``("healthy",) +
LOCATIONS`` (``bearingsim.dataset.CLASSES``)."""

#: where a localized defect can be: a spall on the outer or the inner raceway, a pit on a ball
LOCATIONS = ("outer", "inner", "ball")

__all__ = ["LOCATIONS"]
