"""A ``bearingsim dataset`` file where ML tools expect it: arrays, a label table, and windows.

:func:`load_dataset` reads a data set file (HDF5, written by ``bearingsim dataset``) into NumPy::

    signals, labels, meta = bearingsim.load_dataset("data.h5", split="train")
    signals.shape            # (N, T) float32, m/s^2
    labels["fault_class"]    # (N,) int: index into meta["class_names"]
    meta["sample_rate_Hz"], meta["class_names"], meta["field_units"]["speed_rpm"]

:class:`WindowDataset` cuts the items of one split into windows (a map-style dataset: ``len``,
``ds[k] -> (x, y)``; hand it to ``torch.utils.data.DataLoader`` as it is, torch is not needed to
build it).  The windows of one item stay in that item's split: items, not windows, are assigned
to train / validation / test (``dataset.split_fractions``), so no item's windows straddle two
splits.  With ``features=True`` each window is the vector of :func:`bearingsim.signals.features.window_features`
(names: :data:`bearingsim.signals.features.FEATURE_NAMES`; the fault frequencies of the data set's own
bearing at each item's labelled shaft speed).

Only NumPy and h5py are imported (no JAX) unless ``features=True``.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import failed, InputError

__all__ = ["SPLITS", "load_dataset", "WindowDataset"]

#: split names, in the order of the label field ``split`` (as :data:`bearingsim.datasets.SPLITS`)
SPLITS = ("train", "validation", "test")


def _json_attr(attrs, key, default):
    v = attrs.get(key)
    if v is None:
        return default
    if isinstance(v, bytes):
        v = v.decode()
    try:
        return json.loads(v) if isinstance(v, str) else v
    except ValueError:
        return default


def _split_code(split):
    if split is None:
        return None
    if split not in SPLITS:
        raise InputError(f"split {split!r}: one of None (all items), " + ", ".join(repr(s) for s in SPLITS))
    return SPLITS.index(split)


def load_dataset(path, split: str | None = None, *, include_failed: bool = False):
    """``(signals, labels, metadata)`` of a ``bearingsim dataset`` file.

    ``signals``: (N, T) float32 sensor acceleration in m/s^2, one row per item; ``labels``: the
    structured array of the file's ``/labels`` (fields and units: ``metadata["field_units"]``,
    docs/results.md), the same rows; ``split``: None (every item) or ``"train"``,
    ``"validation"``, ``"test"``.  Items whose simulation failed (label ``result`` != 0: their
    signals are zero) are left out unless ``include_failed``; ``metadata["failed_dropped"]``
    counts them.  ``metadata``: ``sample_rate_Hz``, ``duration_s``, ``class_names`` (list,
    index = ``fault_class``), ``split_names`` (list, index = ``split``), ``field_units`` (dict),
    ``signal_units``, ``result_messages`` ({code: text}), ``rows`` (the file rows taken),
    ``count`` (items in the file), ``seed``, ``bearingsim_version``, ``case_toml`` (the spec),
    ``path``.  A file that is not a data set gets :class:`InputError`.
    """
    import h5py

    p = Path(path)
    code = _split_code(split)
    if not p.is_file():
        raise InputError(f"{p}: no such data set file" + (" (it is a directory)" if p.is_dir() else ""))
    try:
        f = h5py.File(p, "r")
    except OSError as e:
        raise InputError(f"{p}: not an HDF5 data set file ({e})") from None
    with f:
        missing = [k for k in ("signals", "labels") if k not in f]
        if missing or "sample_rate_Hz" not in f.attrs:
            raise InputError(f"{p}: not a bearingsim data set (no {', '.join(missing) or 'sample_rate_Hz'}): "
                             "write one with `bearingsim dataset SPEC -o FILE.h5`")
        lab_all = f["labels"][()]
        keep = np.ones(len(lab_all), bool)
        bad = failed(lab_all["result"]) if "result" in (lab_all.dtype.names or ()) else np.zeros_like(keep)
        if code is not None:
            keep &= lab_all["split"] == code
        dropped = int(np.sum(keep & bad)) if not include_failed else 0
        if not include_failed:
            keep &= ~bad
        rows = np.flatnonzero(keep)
        sig = f["signals"]
        signals = np.asarray(sig[rows] if rows.size else np.zeros((0, sig.shape[1])), dtype=np.float32)
        la = f["labels"].attrs
        classes = _json_attr(la, "class_names", {})
        if isinstance(classes, dict):
            classes = [classes[k] for k in sorted(classes, key=int)]
        messages = {int(k): v for k, v in _json_attr(la, "result_messages", {}).items()}
        attrs = dict(f.attrs)
        meta = {
            "path": str(p),
            "sample_rate_Hz": float(attrs["sample_rate_Hz"]),
            "duration_s": float(attrs.get("duration_s", sig.shape[1] / float(attrs["sample_rate_Hz"]))),
            "class_names": list(classes),
            "split_names": list(SPLITS),
            "split": split,
            "field_units": dict(_json_attr(la, "field_units", {})),
            "signal_units": str(sig.attrs.get("units", "m/s^2")),
            "result_messages": messages,
            "rows": rows,
            "count": int(len(lab_all)),
            "failed_dropped": dropped,
            "seed": int(attrs["seed"]) if "seed" in attrs else None,
            "bearingsim_version": str(attrs.get("bearingsim_version", "")),
            "case_toml": str(attrs.get("case_toml", "")),
        }
    return signals, lab_all[rows], meta


class WindowDataset:
    """Windows of the items of one split of a data set file: ``len(ds)``, ``ds[k] -> (x, y)``.

    ``window_s`` (s) or ``window`` (samples) sets the window length (default: the whole item),
    ``hop_s`` / ``hop`` the step between window starts (default: the window length, no
    overlap); a window never runs past its item's end and never joins two items.  ``x`` is the
    window as float32 of shape (1, window) (a channel axis, as 1-D convolutions expect), or with
    ``features=True`` the float32 vector of :func:`bearingsim.signals.features.window_features` (order:
    :data:`bearingsim.signals.features.FEATURE_NAMES`).  ``y`` is the label field ``target`` of the item
    (default ``fault_class``, an int).  ``groups()`` gives each window's item index (for grouped
    cross-validation); ``arrays()`` all windows at once (X, y) for scikit-learn.
    """

    def __init__(self, path, split: str | None = "train", *, window_s: float | None = None,
                 hop_s: float | None = None, window: int | None = None, hop: int | None = None,
                 features: bool = False, target: str = "fault_class", include_failed: bool = False):
        self.signals, self.labels, self.metadata = load_dataset(path, split, include_failed=include_failed)
        fs = self.metadata["sample_rate_Hz"]
        T = self.signals.shape[1]
        if window is None:
            window = T if window_s is None else int(round(float(window_s) * fs))
        if hop is None:
            hop = window if hop_s is None else int(round(float(hop_s) * fs))
        if not 1 <= int(window) <= T:
            raise InputError(f"window {window} samples: between 1 and the item length {T} samples "
                             f"({T / fs:g} s at {fs:g} Hz)")
        if int(hop) < 1:
            raise InputError(f"hop {hop} samples: >= 1")
        if target not in (self.labels.dtype.names or ()):
            raise InputError(f"target {target!r}: one of the label fields {', '.join(self.labels.dtype.names)}")
        self.window, self.hop, self.target = int(window), int(hop), target
        self.per_item = 1 + (T - self.window) // self.hop
        self.sample_rate_Hz = fs
        self.class_names = self.metadata["class_names"]
        self._features = None
        if features:
            self._features = self._all_features()

    def __len__(self) -> int:
        return len(self.labels) * self.per_item

    def _window(self, k):
        i, w = divmod(k, self.per_item)
        return i, self.signals[i, w * self.hop:w * self.hop + self.window]

    def __getitem__(self, k):
        n = len(self)
        k = int(k)
        if k < 0:
            k += n
        if not 0 <= k < n:
            raise IndexError(f"window {k} of {n}")
        i, x = self._window(k)
        y = self.labels[self.target][i].item()
        if self._features is not None:
            return self._features[k], y
        return x[None, :].astype(np.float32), y

    def groups(self) -> np.ndarray:
        """The item (label ``index``) of every window, in window order."""
        return np.repeat(self.labels["index"], self.per_item)

    def targets(self) -> np.ndarray:
        """The label ``target`` of every window, in window order."""
        return np.repeat(self.labels[self.target], self.per_item)

    def arrays(self):
        """(X, y) of every window: X (n, window) float32, or (n, features) with ``features=True``."""
        if self._features is not None:
            return self._features, self.targets()
        if not len(self):
            return np.zeros((0, self.window), np.float32), self.targets()
        X = np.stack([self._window(k)[1] for k in range(len(self))]).astype(np.float32)
        return X, self.targets()

    def _all_features(self):
        # local: reading a data set imports NumPy and h5py only; the features (and the case
        # they need) load JAX, so only ``features=True`` imports them (the module docstring)
        from ..case import parse_case
        from ..signals.features import FEATURE_NAMES, fault_orders, window_features

        if not len(self):
            return np.zeros((0, len(FEATURE_NAMES)), np.float32)
        case = parse_case(self.metadata["case_toml"], self.metadata["path"])
        orders = fault_orders(case.bearing())
        X = np.stack([self._window(k)[1] for k in range(len(self))]).astype(np.float64)
        shaft = np.repeat(self.labels["shaft_Hz"], self.per_item)
        return window_features(X, self.sample_rate_Hz, shaft, orders).astype(np.float32)
