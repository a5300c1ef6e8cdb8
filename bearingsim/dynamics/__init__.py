"""Dynamic layer (MODEL.md sections 7 and 9): shaft and housing driven by the Jones forces of the
balls as they meet a defect (outer or inner raceway spall, ball pit); the sensor path applied
exactly afterwards.  One concept per module:

=====================  ==========================================================================
``parameters``         result codes, structural parameters, realism ingredients
``motion``             the drawn cage / shaft motion (slip, speed fluctuation) and defect timings
``ball_force``         the lean ball solve of the right-hand side (full, or the chord method from
                       the previous step's balls), and its step-count check
``model``              the shaft/housing equations, their equilibrium at t = 0, linear modes
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
from .motion import (DeviceMotion, Motion, crossings_device, defect_edge_times, defect_pass_times, defect_phase,
                     defect_times_device, device_motion_of, draw_motion, host_motion_of, knot_count, motion_at,
                     motion_at_device, motion_labels, motion_ok_device, pass_count)

# --------------------------------------------------------------------------- ball forces
from .ball_force import (CHORD_TOL, ITER_CHOICES, RECORD_ROWS, REF_ITERATIONS, BallCarry, ball_errors,
                         bearing_force, bearing_force_chord, bearing_force_history, choose_ball_iterations,
                         initial_ball_carry, next_iterations, precompile_ball_check, record_loads_angles)

# -------------------------------------------------------------------------------- model
from .model import DynamicModel, build_model, choose_substeps, initial_state, linear_modes

# --------------------------------------------------------------------------- integration
from .integrate import CHUNK, SCHEMES, edge_fractions, motion_stages, run_adaptive, run_fixed, stage_grid, time_grid

# ------------------------------------------------------------------------- entry points
from .frequencies import characteristic_frequencies, spin_ratio, state_frequencies
from .simulate import (DynamicsResult, ball_records, load_zone_centre, simulate, simulate_case, unbridged_of,
                       finish_record)
from .program import MENU, MOTION_STREAM, ChunkProgram, chunk_program, item_keys, iterations_needed, menu_iterations
from .batch import batch_settings, defect_slots, extreme_items

#: former names (outer-spall era): the times a ball meets a defect's edges / centre
spall_edge_times = defect_edge_times
spall_pass_times = defect_pass_times

__all__ = [
    "RESULTS", "DynamicsError", "DynamicsParameters", "Realism",
    "Motion", "draw_motion", "motion_at", "motion_labels", "defect_phase",
    "defect_edge_times", "defect_pass_times", "spall_edge_times", "spall_pass_times",
    "ITER_CHOICES", "REF_ITERATIONS", "bearing_force", "bearing_force_history", "ball_errors", "choose_ball_iterations", "precompile_ball_check",
    "next_iterations", "RECORD_ROWS", "record_loads_angles",
    "CHORD_TOL", "BallCarry", "initial_ball_carry", "bearing_force_chord",
    "DynamicModel", "build_model", "initial_state", "linear_modes", "choose_substeps",
    "CHUNK", "SCHEMES", "run_fixed", "run_adaptive", "time_grid", "stage_grid", "motion_stages", "edge_fractions",
    "DynamicsResult", "characteristic_frequencies", "spin_ratio", "state_frequencies", "ball_records", "simulate", "simulate_case",
    "load_zone_centre", "unbridged_of", "finish_record",
    "batch_settings", "defect_slots", "extreme_items",
    "DeviceMotion", "motion_at_device", "motion_ok_device", "device_motion_of", "host_motion_of", "knot_count",
    "crossings_device", "defect_times_device", "pass_count",
    "MENU", "MOTION_STREAM", "item_keys", "ChunkProgram", "chunk_program", "iterations_needed", "menu_iterations",
]
