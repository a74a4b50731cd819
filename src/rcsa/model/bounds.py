"""Validation bounds of every request: the one source the library and the REST schemas share.

Physical bounds keep every field within what a machine tool can be (no 22 m holder segment,
no 1e30 kg sensor), with a wide margin so that no real assembly is refused; sanity bounds of
the other quantities lie far outside any machine tool, so that no accepted value can
overflow the arithmetic (2πf, d⁴, k/ω …); size limits bound the work a request may ask
for. Uploaded files meet the same numbers (:mod:`rcsa.model.input_policy`). The parsers
(:mod:`rcsa.model.contract`, the lobes, diagnosis and identification requests) check them,
and ``service/schemas.py`` publishes exactly these numbers in the OpenAPI document, so the
REST schema accepts what the library accepts (``tests/service/test_schema_bounds.py``).

Where a quantity must be positive, the parsers check ``> 0`` first (so that ``0`` and
negative values are told "must be > 0") and the sanity minimum after it.
"""

from __future__ import annotations

__all__ = [
    "MAX_MODAL_STIFFNESS_N_M",
    "MIN_MODAL_STIFFNESS_N_M",
    "MAX_MODAL_MASS_KG",
    "MIN_MODAL_MASS_KG",
    "MAX_MODAL_DAMPING_RATIO",
    "MIN_MODAL_DAMPING_RATIO",
    "MAX_MODAL_FREQUENCY_HZ",
    "MIN_MODAL_FREQUENCY_HZ",
    "MAX_MODAL_TABLE_MODES",
    "MAX_BATCH_COMBINATIONS",
    "MAX_BEARINGS",
    "MAX_COHERENCE",
    "MAX_CONTACT_PRESSURE_PA",
    "MAX_CONFIDENCE",
    "MAX_CUTTING_COEFFICIENT_N_M2",
    "MAX_DAMPING",
    "MAX_DENSITY_KG_M3",
    "MAX_DIAMETER_M",
    "MAX_FREQUENCY_HZ",
    "MAX_FREQUENCY_LINES",
    "MAX_FRF_VALUE",
    "MAX_HOLDER_SEGMENTS_PER_CONE",
    "MAX_INTERFACE_STIFFNESS_N_M3",
    "MAX_CONTACT_ARC_DEG",
    "MAX_INTERFACE_STIFFNESS_SCALE",
    "MAX_INTERFACE_TANGENTIAL_RATIO",
    "MAX_JSON_CONTAINERS",
    "MAX_JSON_DEPTH",
    "MAX_JSON_ITEMS",
    "MAX_LIBRARY_ITEMS",
    "MAX_JSON_NUMBER",
    "MAX_LENGTH_M",
    "MAX_LOSS_FACTOR",
    "MAX_MODULUS_PA",
    "MAX_NECK_SEGMENTS",
    "MAX_POISSON_RATIO",
    "MAX_RADIAL_RATIO",
    "MAX_RELATIVE_STEP",
    "MAX_SEGMENTS",
    "MAX_SHEAR_COEFFICIENT",
    "MAX_SENSOR_MASS_KG",
    "MAX_SPEED_COUNT",
    "MAX_SPEED_RPM",
    "MAX_TAP_SAMPLES",
    "MAX_STRING_CHARS",
    "MAX_STIFFNESS",
    "MAX_SURFACE_ROUGHNESS_M",
    "MAX_TEETH",
    "MAX_TOLERANCE",
    "MAX_TOLERANCE_STICKOUT_M",
    "MAX_UNCERTAINTY_DRAWS",
    "MAX_UNCERTAINTY_DRAW_LINES",
    "MAX_UNCERTAINTY_SEED",
    "MIN_CONFIDENCE",
    "MIN_CONTACT_PRESSURE_PA",
    "MIN_CUTTING_COEFFICIENT_N_M2",
    "MIN_DENSITY_KG_M3",
    "MIN_FLUTED_DIAMETER_RATIO",
    "MIN_FREQUENCY_HZ",
    "MIN_INTERFACE_STIFFNESS_N_M3",
    "MIN_CONTACT_ARC_DEG",
    "MIN_INTERFACE_STIFFNESS_SCALE",
    "MIN_INTERFACE_TANGENTIAL_RATIO",
    "MIN_JOINT_STIFFNESS",
    "MIN_LENGTH_M",
    "MIN_MODULUS_PA",
    "MIN_POISSON_RATIO",
    "MIN_RADIAL_IMMERSION",
    "MIN_RELATIVE_STEP",
    "MIN_SHEAR_COEFFICIENT",
    "MIN_SPEED_COUNT",
    "MIN_SPEED_RPM",
    "MIN_SURFACE_ROUGHNESS_M",
    "MIN_UNCERTAINTY_DRAWS",
    "UNCERTAINTY_SOLVERS",
]

# ---------------------------------------------------------------------------- JSON documents

#: Deepest nesting of objects and lists in a JSON request (a Fusion tool library inside a
#: request is 8 deep); deeper documents are refused before anything recurses into them.
MAX_JSON_DEPTH = 32
#: Largest magnitude of any number in a JSON request. No quantity of this domain comes near
#: it in SI units (the largest bounds below are 1e15); it keeps every power a computation
#: may take of an unchecked number (x^10 = 1e300) finite. Integers beyond 64 bits and
#: NaN/Infinity tokens are refused by the decoder itself.
MAX_JSON_NUMBER = 1.0e30
#: Longest string (or object key) of a JSON document, characters: names, notes, vendor
#: descriptions and expressions are far shorter; the stored metadata of a measurement is an
#: HDF5 attribute, which holds at most 64 KiB.
MAX_STRING_CHARS = 16_384
#: Most objects and arrays in one JSON document, counted on its raw text before it is parsed
#: (:class:`rcsa.model.input_policy.JsonCounter`). A 10 000-combination batch of RA-1-like
#: tools holds 100 000 of them and a Fusion library ~11 per tool; a parsed object costs ~200
#: bytes, so the bound keeps what a document can make a process allocate near 50 MB (a 4 MiB
#: body of 520 000 tiny objects is refused while it arrives, before any is made).
MAX_JSON_CONTAINERS = 250_000
#: Most elements of objects and arrays in one JSON document (counted on the raw text as the
#: commas between them plus one per object or array): a measured point receptance of
#: :data:`MAX_FREQUENCY_LINES` lines holds 1.8 million numbers (lines and four complex
#: receptances), a 10 000-combination batch 370 000; a parsed number costs ~32 bytes.
MAX_JSON_ITEMS = 4_000_000

# ---------------------------------------------------------------------------- sizes

#: Frequency lines of one request, and rows of one measured FRF file (CSV/TSV, CutPro, UFF,
#: measurement JSON): an analyser's longest FRF export is 25 600 lines (102 400 with zoom).
MAX_FREQUENCY_LINES = 200_000
#: Samples (rows) of one raw tap-test file: 10 s at 200 kHz, beyond any impact record
#: (a hammer tap rings out in well under a second).
MAX_TAP_SAMPLES = 2_000_000
#: Tool–holder combinations of one batch.
MAX_BATCH_COMBINATIONS = 10_000
#: Items (tools, holders, anything) of one CAM tool library: twice the combinations a request may
#: predict, as a library holds holders and tools that are skipped besides (a workshop's library
#: has hundreds). Checked before any item is looked at.
MAX_LIBRARY_ITEMS = 2 * MAX_BATCH_COMBINATIONS
#: Segments of one spindle or one holder. Real spindle models have 10–60 and a CAM
#: holder cut into cylinders a few hundred; each segment costs a 4×4 solve per line.
MAX_SEGMENTS = 1_000
#: Bearings of one spindle.
MAX_BEARINGS = 100

# ---------------------------------------------------------------------------- assembly

#: Lowest first line and highest line of a frequency grid, Hz (0 Hz is singular).
MIN_FREQUENCY_HZ, MAX_FREQUENCY_HZ = 1.0e-3, 1.0e7
#: Shortest and longest length (segment, tool, stickout, bearing position) or diameter, m.
#: The longest spindle shaft of a boring mill is about 2 m; holders and tools are shorter
#: than 1 m.
MIN_LENGTH_M, MAX_LENGTH_M = 1.0e-6, 3.0
#: Largest diameter of a spindle, holder or tool section, m (a face-mill spindle nose is
#: 0.2–0.3 m).
MAX_DIAMETER_M = 1.0
#: Largest accelerometer (with its mounting) on a tap-tested structure, kg: tap-test
#: accelerometers weigh 0.2–50 g.
MAX_SENSOR_MASS_KG = 1.0
#: Young's modulus, Pa.
MIN_MODULUS_PA, MAX_MODULUS_PA = 1.0, 1.0e13
#: Density, kg/m³.
MIN_DENSITY_KG_M3, MAX_DENSITY_KG_M3 = 1.0e-3, 1.0e5
#: Poisson's ratio, both exclusive (dimensionless).
MIN_POISSON_RATIO, MAX_POISSON_RATIO = -1.0, 0.5
#: Loss factor η, exclusive (dimensionless; 0 included).
MAX_LOSS_FACTOR = 1.0
#: Largest stiffness (bearings and joints), N/m or N·m/rad.
MAX_STIFFNESS = 1.0e15
#: Smallest stiffness of an elastic joint, N/m or N·m/rad (a bearing may have 0).
MIN_JOINT_STIFFNESS = 1.0e-3
#: Largest viscous damping, N·s/m or N·m·s/rad.
MAX_DAMPING = 1.0e12
#: Interface stiffness per unit area of a holder–tool contact (``joints.holder_tool``,
#: model ``contact``), N/m³: from a soft polymer layer (1e9) to far stiffer than any
#: machined steel contact (1e17; measured shrink-fit and collet interfaces lie near 1e13–1e15).
MIN_INTERFACE_STIFFNESS_N_M3, MAX_INTERFACE_STIFFNESS_N_M3 = 1.0e9, 1.0e17
#: A factor on a clamping's whole interface stiffness (dimensionless; what an identification finds).
MIN_INTERFACE_STIFFNESS_SCALE, MAX_INTERFACE_STIFFNESS_SCALE = 1.0e-4, 1.0e2
#: Tangential over normal interface stiffness (dimensionless; 2(1−ν)/(2−ν) ≈ 0.8 for elastic
#: asperity contact of steels).
MIN_INTERFACE_TANGENTIAL_RATIO, MAX_INTERFACE_TANGENTIAL_RATIO = 1.0e-3, 10.0
#: Arc of the bore's circumference a clamping's contact covers, degrees (a side-lock pushes the
#: shank against one side of its bore: 90–180°; 360: all round).
MIN_CONTACT_ARC_DEG, MAX_CONTACT_ARC_DEG = 10.0, 360.0
#: Nominal contact pressure of a clamping, Pa (a contact model's input).
MIN_CONTACT_PRESSURE_PA, MAX_CONTACT_PRESSURE_PA = 1.0e3, 2.0e9
#: RMS roughness scale of the contacting surfaces, m (a contact model's input).
MIN_SURFACE_ROUGHNESS_M, MAX_SURFACE_ROUGHNESS_M = 1.0e-9, 1.0e-4
#: Pieces of a tool's stepped neck (``tool.neck_segments``).
MAX_NECK_SEGMENTS = 200
#: Smallest equivalent fluted diameter over the cutting diameter (the largest is 1).
MIN_FLUTED_DIAMETER_RATIO = 0.01
#: A numeric shear coefficient κ (dimensionless).
MIN_SHEAR_COEFFICIENT, MAX_SHEAR_COEFFICIENT = 0.01, 1.5

# ---------------------------------------------------------------------------- measured FRFs

#: Largest magnitude of the real or imaginary part of an inline FRF value, m/N.
MAX_FRF_VALUE = 1.0e6
#: Largest ordinary coherence γ²: 1, and estimates may exceed it by rounding
#: (|Sxy|² / (Sxx Syy)); allow that much.
MAX_COHERENCE = 1.0 + 1e-9

# ---------------------------------------------------------------------------- stability lobes

#: Teeth (flutes) of a cutter.
MAX_TEETH = 100
#: Tangential cutting coefficient Kt, N/m².
MIN_CUTTING_COEFFICIENT_N_M2, MAX_CUTTING_COEFFICIENT_N_M2 = 1.0, 1.0e15
#: Radial to tangential coefficient ratio Kr (dimensionless; 0 included).
MAX_RADIAL_RATIO = 1000.0
#: Smallest radial immersion a_e/D (the largest is 1, slotting).
MIN_RADIAL_IMMERSION = 1.0e-4
#: Spindle speeds of a lobes grid, rpm.
MIN_SPEED_RPM, MAX_SPEED_RPM = 1.0e-3, 1.0e6
#: Speeds of a lobes grid.
MIN_SPEED_COUNT, MAX_SPEED_COUNT = 2, 100_000
#: Rows of a modal table of one direction (a lobes request's ``modal_x`` / ``modal_y``).
MAX_MODAL_TABLE_MODES = 64
#: A modal table's natural frequencies (Hz), damping ratios, modal masses (kg) and modal
#: stiffnesses (N/m).
MIN_MODAL_FREQUENCY_HZ, MAX_MODAL_FREQUENCY_HZ = 1.0, 1.0e5
MIN_MODAL_DAMPING_RATIO, MAX_MODAL_DAMPING_RATIO = 1.0e-5, 0.95
MIN_MODAL_MASS_KG, MAX_MODAL_MASS_KG = 1.0e-9, 1.0e6
MIN_MODAL_STIFFNESS_N_M, MAX_MODAL_STIFFNESS_N_M = 1.0, MAX_STIFFNESS

# ---------------------------------------------------------------------------- effect analysis

#: Relative step δ of the effect analysis' central differences in ln(parameter). Natural
#: frequencies are bisected to 1e-11 relative, so below 1e-6 their rounding (1e-11/δ)
#: would reach 1e-5 of a sensitivity; above 0.1 the truncation error (δ²) does.
MIN_RELATIVE_STEP, MAX_RELATIVE_STEP = 1.0e-6, 0.1

# ---------------------------------------------------------------------------- tool libraries

#: Cylinders per conical holder segment of a CAM library's holder.
MAX_HOLDER_SEGMENTS_PER_CONE = 50

# ---------------------------------------------------------------------------- uncertainty

#: Monte-Carlo draws of one uncertainty request (band, natural frequencies, robust lobes):
#: percentiles need a few; a thousand give p05/p95 to about ±1 percentile point.
MIN_UNCERTAINTY_DRAWS, MAX_UNCERTAINTY_DRAWS = 2, 1000
#: Compute budget of one uncertain assembly: draws × frequency lines (each draw is a full
#: solve of every line; 2 000 000 is 1 000 draws of 2 000 lines, ~10 s on the reference machine).
MAX_UNCERTAINTY_DRAW_LINES = 2_000_000
#: Largest seed of the draws' random generator (an unsigned 32-bit integer).
MAX_UNCERTAINTY_SEED = 2**32 - 1
#: How a band's draws are solved (the option's ``solver``): by the reduced model (each draw
#: exactly at a few lines, fitted rationally; the default) or every draw exactly on every line.
UNCERTAINTY_SOLVERS = ("reduced", "exact")
#: One standard deviation of a tolerance: relative (``_rel``) and log-scale (``_log``) ones,
#: dimensionless, and the stickout's, m (the diagnosis accepts the same).
MAX_TOLERANCE = 2.0
MAX_TOLERANCE_STICKOUT_M = 0.05
#: Confidence of a robust (percentile) depth limit: from the median to 99.9 %.
MIN_CONFIDENCE, MAX_CONFIDENCE = 0.5, 0.999
