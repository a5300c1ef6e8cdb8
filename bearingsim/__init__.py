"""bearingsim: angular contact ball bearings with an outer-raceway spall.

Pipeline: geometry -> hertz -> jones (+defect) -> sweep -> dynamics -> signal,
with case/io/plots/cli at the edge.  The core (everything up to ``signal``)
is pure JAX in float64 and knows nothing of files or printing.
"""
import jax as _jax

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
