import numpy as np
import pytest

import bearingsim as bs


def harris218(n_balls=16, **kw):
    """Harris & Kotzalas' 218 angular contact ball bearing (reference-data.md)."""
    return bs.Bearing(n_balls, 22.225e-3, 125.26e-3, 0.5232, 0.5232, np.deg2rad(40.0), **kw)


@pytest.fixture(scope="session")
def b218():
    return harris218()
