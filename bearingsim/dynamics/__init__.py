"""Dynamic layer (docs/model.md sections 7 and 9): shaft and housing driven by the Jones forces of the
balls as they meet a defect (outer or inner raceway spall, ball pit); the sensor path applied
exactly afterwards.  One concept per module:

=====================  ==========================================================================
``parameters``         result codes, structural parameters, realism ingredients
``motion``             the drawn cage / shaft motion (slip, speed fluctuation) and defect timings
``ball_force``         the lean ball solve of the right-hand side (full, or the chord method from
                       the previous step's balls), and its step-count check
``model``              the shaft/housing equations, their equilibrium at t = 0, linear modes
``sensor``             the linear sensor path applied exactly after the integration, measurement noise
``passes``             pass-to-pass variability of a defect's impacts (a run's and a data set item's)
``integrate``          fixed-step chunked time loop (and the adaptive diffrax reference)
``frequencies``        the defect frequencies at a quasi-static state (one JAX version)
``simulate``           one simulation: :func:`simulate`, :class:`DynamicsResult`
``program``            a data set chunk as compiled device programs: :func:`chunk_program`
``batch``              what a chunk fixes before it runs: defect slots, bounding items, substeps
=====================  ==========================================================================
"""
# ---------------------------------------------------------------- parameters and results
from .parameters import RESULTS, DynamicsError, DynamicsParameters, Realism

# ------------------------------------------------------------------------------ motion
from .motion import (Motion, crossings, defect_edge_times, defect_pass_times, defect_times, draw_motion, knot_count,
                     motion_at, motion_labels, motion_ok, pad_knots, pass_count, run_labels)

# --------------------------------------------------------------------------- ball forces
from .ball_force import (CHORD_TOL, ITER_CHOICES, RECORD_ROWS, REF_ITERATIONS, BallCarry, ball_errors,
                         bearing_force, bearing_force_chord, bearing_force_history, choose_ball_iterations,
                         initial_ball_carry, next_iterations, precompile_ball_check, record_loads_angles)

# -------------------------------------------------------------------------------- model
from .model import DynamicModel, build_model, choose_substeps, initial_state, linear_modes

# ---------------------------------------------------------------- sensor path and passes
from .sensor import measurement_noise, sensor_filter
from .passes import PassSettings, pass_variability

# --------------------------------------------------------------------------- integration
from .integrate import CHUNK, SCHEMES, edge_fractions, motion_stages, run_adaptive, run_fixed, stage_grid, time_grid

# ------------------------------------------------------------------------- entry points
from .frequencies import characteristic_frequencies, spin_ratio, state_frequencies
from .simulate import (DynamicsResult, ball_records, load_zone_centre, simulate, unbridged_of,
                       finish_record)
from .program import MENU, MOTION_STREAM, ChunkProgram, chunk_program, item_keys, iterations_needed, menu_iterations
from .batch import batch_settings, defect_slots, extreme_items

__all__ = [
    "RESULTS", "DynamicsError", "DynamicsParameters", "Realism",
    "Motion", "draw_motion", "motion_at", "motion_labels", "run_labels", "pad_knots",
    "defect_edge_times", "defect_pass_times",
    "ITER_CHOICES", "REF_ITERATIONS", "bearing_force", "bearing_force_history", "ball_errors", "choose_ball_iterations", "precompile_ball_check",
    "next_iterations", "RECORD_ROWS", "record_loads_angles",
    "CHORD_TOL", "BallCarry", "initial_ball_carry", "bearing_force_chord",
    "DynamicModel", "build_model", "initial_state", "linear_modes", "choose_substeps",
    "measurement_noise", "sensor_filter", "PassSettings", "pass_variability",
    "CHUNK", "SCHEMES", "run_fixed", "run_adaptive", "time_grid", "stage_grid", "motion_stages", "edge_fractions",
    "DynamicsResult", "characteristic_frequencies", "spin_ratio", "state_frequencies", "ball_records", "simulate",
    "load_zone_centre", "unbridged_of", "finish_record",
    "batch_settings", "defect_slots", "extreme_items",
    "motion_ok", "knot_count", "crossings", "defect_times", "pass_count",
    "MENU", "MOTION_STREAM", "item_keys", "ChunkProgram", "chunk_program", "iterations_needed", "menu_iterations",
]
