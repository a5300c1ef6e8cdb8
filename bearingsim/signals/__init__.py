"""From the dynamics' forces to a sensor record and its features: the signal stage.  Core
(imports only ``physics`` and the infrastructure, never the dynamics).  The modules:

``sensor``       the linear sensor path applied exactly after the integration, measurement noise
``background``   the machine's own vibration in every record: its description and ranges
``nuisance``     what real bearings add to a fault's clean signature (JAX, keyed)
``signal_stage`` a record's whole signal stage on the device, every draw from its key: pass-to-pass
                 variability and strikes, noise, background, fault level (a data set item's and a
                 single simulation's; the NumPy versions are the tests' oracles, tests/oracles/)
``envelope``     envelope analysis on NumPy arrays: band-pass, squared envelope, spectra, lines
``features``     the window features a classifier sees
``plain_features`` a plain, fixed feature set (envelope line strengths), the second classifier's
"""
