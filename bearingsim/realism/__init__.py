"""The simulation against real records (edge): the rig's record pipeline, reading a machine's
records, calibrating a data set to them, the sim-to-real transfer benchmark and identifying a
fault from a record.  Builds on the core, ``case``, ``output`` and ``datasets``.

``rig_record``      a case simulated and decimated like the CWRU acquisition (the pit and pass
                    vocabulary re-exported; its names are offered here too: ``simulate_record``)
``records``         record files of the user's machine (.npz, .npy, .csv, .wav)
``calibration``     the CWRU records and their metrics for the calibration
``background_fit``  a machine's background fitted from a healthy record
``machine``         a data set spec calibrated to the user's machine
``transfer``        classifiers trained on simulated windows, tested on real records
``fault_size``      the physics of an identified fault (length, contact angle)
``identify``        a fault's class, size and operating point from a record
``record_spectrum`` a real record against a bearing's fault lines
``detection``       a fault line's verdict at a stated false-alarm rate
"""


def __getattr__(name):
    # the names of the flat module ``bearingsim.realism`` before the folders (simulate_record, ...)
    import importlib

    rig_record = importlib.import_module(f"{__name__}.rig_record")
    if not name.startswith("_") and hasattr(rig_record, name):
        return getattr(rig_record, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
