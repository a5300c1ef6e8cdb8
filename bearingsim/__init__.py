"""bearingsim: angular contact ball bearings with an outer-raceway spall.

Pipeline: geometry -> hertz -> jones (+defect) -> sweep -> dynamics -> signal,
with case/io/plots/cli at the edge.  The core (everything up to ``signal``)
is pure JAX in float64 and knows nothing of files or printing.
"""
import os as _os
import sys as _sys

if _os.path.basename(_sys.argv[0] if _sys.argv else "") == "bearingsim" and "__mp_main__" not in _sys.modules:
    # the `bearingsim` command (not its Dask worker processes): Ctrl-C / SIGTERM while the
    # libraries load (nothing is written yet) is one line and exit 130; bearingsim.cli.main
    # installs its own handlers once they are loaded
    import signal as _signal

    def _stopped_while_loading(signum, frame):
        _os.write(2, f"bearingsim: {_signal.Signals(signum).name}: interrupted while starting; "
                     "nothing written\n".encode())
        _os._exit(130)

    for _sg in (_signal.SIGINT, _signal.SIGTERM):
        _signal.signal(_sg, _stopped_while_loading)

import jax as _jax  # noqa: E402

_jax.config.update("jax_enable_x64", True)

from ._version import __version__  # noqa: E402
from .geometry import Bearing, Material, STEEL, SILICON_NITRIDE  # noqa: E402
from .hertz import (  # noqa: E402
    ellipk_ellipe,
    ellipticity,
    contact_constant,
    hertz_contact,
    HertzContact,
    dimensionless_hertz,
)
from .kinematics import (  # noqa: E402
    Operation,
    ball_kinematics,
    defect_frequencies,
    DefectFrequencies,
)
from .defect import Spall, NO_SPALL, depth_profile, contact_depths  # noqa: E402
from .errors import (  # noqa: E402
    BearingsimError,
    InputError,
    NotConvergedError,
    InvalidStateError,
    OutputError,
)
from .balls import BallState, balls_at, reactions_from_balls  # noqa: E402
from .jones import (  # noqa: E402
    JonesSolution,
    RESULTS,
    OverloadWarning,
    solve,
    solve_state,
    solve_batch,
    ring_reactions,
    load_vector,
    Loads,
)

__all__ = [
    "__version__",
    "Bearing",
    "Material",
    "STEEL",
    "SILICON_NITRIDE",
    "ellipk_ellipe",
    "ellipticity",
    "contact_constant",
    "hertz_contact",
    "HertzContact",
    "dimensionless_hertz",
    "Operation",
    "ball_kinematics",
    "defect_frequencies",
    "DefectFrequencies",
    "Spall",
    "NO_SPALL",
    "depth_profile",
    "contact_depths",
    "BearingsimError",
    "InputError",
    "NotConvergedError",
    "InvalidStateError",
    "OutputError",
    "BallState",
    "balls_at",
    "reactions_from_balls",
    "JonesSolution",
    "RESULTS",
    "OverloadWarning",
    "solve_state",
    "load_vector",
    "solve",
    "solve_batch",
    "ring_reactions",
    "Loads",
]
