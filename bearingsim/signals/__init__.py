"""From the dynamics' records to a data set item's signal and its features: the signal stage.
Core, after the dynamics in the flow (imports ``physics``, ``dynamics`` and the infrastructure;
the sensor path and the pass-to-pass variability a single run shares with a data set item live
in ``dynamics.sensor`` and ``dynamics.passes``).  The modules:

``background``   the machine's own vibration in every record: its description and ranges
``nuisance``     what real bearings add to a fault's clean signature (JAX, keyed)
``signal_stage`` a data set item's whole signal stage on the device, every draw from its key:
                 pass-to-pass variability and strikes, noise, background, fault level (the NumPy
                 versions are the tests' oracles, tests/oracles/)
``envelope``     envelope analysis on NumPy arrays: band-pass, squared envelope, spectra, lines
``features``     the window features a classifier sees
``plain_features`` a plain, fixed feature set (envelope line strengths), the second classifier's
"""
