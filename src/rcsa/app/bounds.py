"""The validation bounds of every request, as the library checks them (:mod:`rcsa.model.bounds`).

The REST schemas publish these numbers in the OpenAPI document, so that the schema accepts
exactly what the library accepts. The semi-discretization lobes' options keep their bounds
beside their solver (:mod:`rcsa.analysis.lobes.options`); they are published here under
``SDM_`` names.

The analyses' own limits (diagnosis options and tolerances, identification and effect
requests) are listed below as the parsers in :mod:`rcsa.analysis` check them; importing
those modules here would load SciPy's optimisers into every process that only validates,
so the numbers are repeated, and ``tests/service/test_schema_bounds.py`` probes each one
against the parser (a value just inside accepted, one just outside refused).
"""

from __future__ import annotations

from rcsa.analysis.lobes.modal_model import (
    DEFAULT_MODES_PER_DIRECTION as SDM_DEFAULT_MODES_PER_DIRECTION,
)
from rcsa.analysis.lobes.options import MAX_MODES_PER_DIRECTION as SDM_MAX_MODES_PER_DIRECTION
from rcsa.analysis.lobes.options import MAX_STEPS_PER_PERIOD as SDM_MAX_STEPS_PER_PERIOD
from rcsa.analysis.lobes.options import MIN_MODES_PER_DIRECTION as SDM_MIN_MODES_PER_DIRECTION
from rcsa.analysis.lobes.options import MIN_STEPS_PER_PERIOD as SDM_MIN_STEPS_PER_PERIOD
from rcsa.model.bounds import *  # noqa: F403 (the whole table, by design)
from rcsa.model.bounds import __all__ as _MODEL_BOUNDS

__all__ = [*_MODEL_BOUNDS, "SDM_DEFAULT_MODES_PER_DIRECTION",
           "SDM_MAX_MODES_PER_DIRECTION", "SDM_MAX_STEPS_PER_PERIOD", "SDM_MIN_MODES_PER_DIRECTION",
           "SDM_MIN_STEPS_PER_PERIOD", "ANALYSIS_MAX_MEASUREMENTS", "DIAGNOSIS_EFFECTS", "DIAGNOSIS_LIKELIHOODS",
           "DIAGNOSIS_OPTION_BOUNDS", "DIAGNOSIS_TOLERANCES", "EFFECTS_MAX_RELATIVE_STEP",
           "IDENTIFIABLE_PARAMETERS", "IDENTIFICATION_MIN_LINES", "TOOL_OVERRIDES"]

#: Tap tests of one diagnosis or identification (``rcsa.analysis.measured_tool_point.MAX_TAP_TESTS``).
ANALYSIS_MAX_MEASUREMENTS = 20
#: Fields of the base tool a tap test may override (``measured_tool_point.TOOL_OVERRIDES``).
TOOL_OVERRIDES = ("material", "diameter_m", "shank_diameter_m", "overall_length_m", "flute_length_m",
                  "stickout_m", "fluted_diameter_ratio", "fluted_mass_diameter_ratio",
                  "shoulder_length_m", "shoulder_diameter_m")
#: Candidate effects a diagnosis may be limited to (``diagnosis.candidates.CANDIDATE_NAMES``).
DIAGNOSIS_EFFECTS = ("holder_tool_joint", "spindle_holder_joint", "bearings", "shear_and_rotary_inertia",
                     "fluted_section", "insertion_depth", "sensor_mass", "joint_damping",
                     "spindle_rotational_receptance", "clamping_model", "interface_scale")
DIAGNOSIS_LIKELIHOODS = ("student_t", "gaussian")
#: Diagnosis tolerances (1σ) and the largest value of each (``diagnosis.request.parse_request``).
DIAGNOSIS_TOLERANCES = dict.fromkeys((
    "tool_youngs_modulus_rel", "tool_density_rel", "structure_youngs_modulus_rel", "structure_density_rel",
    "loss_factor_log", "bearing_stiffness_log", "bearing_damping_log", "spindle_holder_stiffness_log",
    "spindle_holder_damping_log", "holder_tool_stiffness_log", "holder_tool_damping_log",
    "spindle_effective_length_log", "spindle_rotation_shape_log", "spindle_noise_rel"), 2.0) | {"stickout_m": 0.05}
#: (lowest, highest) of the numeric diagnosis options (``diagnosis.request._options``).
DIAGNOSIS_OPTION_BOUNDS = {"monte_carlo_draws": (50.0, 5000.0), "claim_threshold": (0.0, 50.0),
                           "ambiguity_window": (0.0, 50.0), "max_effects": (1.0, 2.0), "max_lines": (200.0, 20000.0)}
#: Fewest frequency lines of an identification's tap test (``joint_identification.request.MIN_LINES``).
IDENTIFICATION_MIN_LINES = 16
#: Joint parameters an identification estimates (``joint_identification.request.IDENTIFIABLE``).
IDENTIFIABLE_PARAMETERS = ("spindle_holder.stiffness_n_m", "spindle_holder.damping_ns_m",
                           "holder_tool.stiffness_n_m", "holder_tool.damping_ns_m",
                           "holder_tool.interface_stiffness_scale")
#: Largest finite-difference step of an effect analysis (``sensitivity.effect_analysis``).
EFFECTS_MAX_RELATIVE_STEP = MAX_RELATIVE_STEP  # noqa: F405 (from rcsa.model.bounds)
