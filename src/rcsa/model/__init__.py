"""The model: the contract's documents parsed into typed specs, assemblies and predictions.

Modules: :mod:`.contract` (assembly documents → immutable specs), :mod:`.bounds` (the one
source of validation bounds), :mod:`.wire` (the one wire form of complex arrays),
:mod:`.assembly` (specs → solvable chains), :mod:`.prediction` (the tool-point result),
:mod:`.spindle_side` (an analytical spindle or a measured base), :mod:`.batch` (many
combinations on one spindle), :mod:`.peaks` (peaks and single-mode fits),
:mod:`.parameters` (named parameters), :mod:`.receptance_coupling` (the paper's RCSA path),
:mod:`.reference` (RA-1).
"""
