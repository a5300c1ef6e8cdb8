"""From the dynamics' forces to a sensor record and its features: the signal stage.  Core
(imports only ``physics`` and the infrastructure, never the dynamics).  The modules:

``sensor``       the linear sensor path applied exactly after the integration, measurement noise
``passes``       pass-to-pass variability of a defect's impacts, the strike of a ball pit
``background``   the machine's own vibration in every record
``nuisance``     what real bearings add to a fault's clean signature (JAX, keyed)
``signal_stage`` a data set item's whole signal stage on the device (JAX twins of the above)
``envelope``     envelope analysis on NumPy arrays: band-pass, squared envelope, spectra, lines
``features``     the window features a classifier sees
"""
