"""The items' random keys and the one registry of their sub-streams.

An item of a data set (or of a study) is a pure function of (spec, seed, index): its key is
``jax.random.fold_in(jax.random.PRNGKey(seed), index)`` (:func:`item_keys`, raw (N, 2) uint32
key data), and every random draw of the item comes from its own sub-stream
``jax.random.fold_in(key, STREAMS[name])`` (:func:`stream_key`).  Every module that draws from an
item's key takes its stream number from :data:`STREAMS` here, so that no two draws share a
stream (shared numbers give correlated draws).  Never renumber a stream (the data set version
would change); add new ones with new numbers.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from .programs import jit

__all__ = ["STREAMS", "item_keys", "stream_key"]

#: name -> sub-stream number (``fold_in(item key, number)``); all distinct
STREAMS = {
    # the label draws of bearingsim.datasets.spec
    "speed_rpm": 0, "radial_N": 1, "axial_N": 2, "spall_length_mm": 3, "spall_depth_mm": 4,
    "spall_center_deg": 5, "outer_position": 6, "signal_gain": 7, "snr_dB": 8, "strike_probability": 9,
    "split": 10, "realism_seed": 11, "transfer_path": 12,
    # the dynamics (bearingsim.dynamics.motion: slip walk, speed fluctuation)
    "motion": 13,
    # the signal stage (bearingsim.signals.signal_stage)
    "noise": 14, "passes": 15, "strike": 16, "background": 17, "randomisation": 18, "transfer": 19,
    # issue 26's ingredients (bearingsim.signals.nuisance)
    "nuisance": 20,
    # issue 33: a ball pit's kinematic exposure pass by pass (bearingsim.dynamics.exposure)
    "ball_exposure": 21,
}
assert len(set(STREAMS.values())) == len(STREAMS), "stream numbers must be distinct"


def _item_keys(seed, index):
    base = jax.random.PRNGKey(seed)
    return jax.vmap(lambda i: jax.random.fold_in(base, i))(index.astype(jnp.uint32))


#: a kept program (bearingsim.programs): a host call loads it instead of tracing a vmap each time;
#: inside another program it is inlined
_item_keys_jit = jit(_item_keys)


def item_keys(seed, index):
    """(N, 2) uint32 keys of the items ``index`` of a run seeded ``seed``:
    ``fold_in(PRNGKey(seed), i)`` (depends on (seed, index) only, not on the chunk)."""
    if isinstance(seed, jax.core.Tracer) or isinstance(index, jax.core.Tracer):
        return _item_keys(jnp.asarray(seed), jnp.asarray(index))
    return _item_keys_jit(np.int64(int(seed)), np.asarray(index, np.uint32))


def stream_key(key, name):
    """The item key's sub-stream ``name`` (:data:`STREAMS`)."""
    return jax.random.fold_in(key, STREAMS[name])
