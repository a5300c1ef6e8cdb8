"""The names every layer shares, importable without JAX (the command line's parser builds its
choices from them before any JAX import): the defect locations, in the order of the fault classes.

``bearingsim.physics.defect.LOCATIONS`` is this tuple; the fault classes of a data set item, an
identification and the transfer benchmark are :data:`CLASSES` (one definition: every module
imports it from here), their numbers :data:`CLASS_NUMBER`."""

#: where a localized defect can be: a spall on the outer or the inner raceway, a pit on a ball
LOCATIONS = ("outer", "inner", "ball")

#: the fault classes, index = ``fault_class`` of a data set item: healthy, then the locations
CLASSES = ("healthy",) + LOCATIONS

#: class name -> its number (``fault_class``): use these instead of bare integers
CLASS_NUMBER = {name: number for number, name in enumerate(CLASSES)}

__all__ = ["LOCATIONS", "CLASSES", "CLASS_NUMBER", "noun_module", "lazy_exports"]


def noun_module(module_name: str, noun: str):
    """Make module ``module_name`` answer to its ``noun``: calling the module calls its function of
    that name (``bearingsim.sweep(...)`` is ``bearingsim.physics.sweep.sweep(...)``).  The package exports
    these nouns; Python rebinds ``bearingsim.<name>`` to the submodule whenever it is imported, so
    the module itself must answer.  Called at the end of the module."""
    import sys
    import types

    module = sys.modules[module_name]

    class NounModule(types.ModuleType):
        __doc__ = module.__doc__

        def __call__(self, *args, **kwargs):
            return getattr(self, noun)(*args, **kwargs)

    NounModule.__module__ = module_name
    module.__class__ = NounModule
    return module


def lazy_exports(package: str, table: dict, missing=None):
    """``(__getattr__, __dir__)`` for a package whose public names are imported at first use
    (PEP 562): ``table`` maps a submodule (relative dotted name) to the names it offers.  A name
    found is kept in the package's namespace (the next access is a plain lookup); ``missing(name)``
    answers a name the table does not hold (or raises ``AttributeError``)."""
    import importlib
    import sys

    where = {name: mod for mod, names in table.items() for name in names}

    def __getattr__(name):
        mod = where.get(name)
        if mod is None:
            if missing is not None:
                return missing(name)
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f".{mod}", package), name)
        vars(sys.modules[package])[name] = value
        return value

    def __dir__():
        return sorted(set(vars(sys.modules[package])) | set(where))

    return __getattr__, __dir__
