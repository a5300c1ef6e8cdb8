"""What a run leaves behind for a person: results files, printed text and figures (edge).  Knows
the case layer and the core; the workflows (``bearingsim.app``) call it.

``io``           results files: JSON and HDF5 layouts with units, atomic writes, no NaN
``report``       the text the commands print
``plots``        figures of quasi-static states, sweeps, studies, simulations, comparisons
``plots_signal`` envelope spectra with fault markers, time histories, transfer figures
"""
