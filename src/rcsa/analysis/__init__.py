"""Analyses built on predictions: sensitivities, joint identification, diagnosis, lobes.

Modules and packages: :mod:`.mode_features` (modes of an exact model),
:mod:`.sensitivity` (effect analysis), :mod:`.joint_identification`,
:mod:`.measured_tool_point` (tap tests in requests), :mod:`.diagnosis` (the sim-to-real gap,
with its candidate catalogue), :mod:`.lobes` (stability lobes), :mod:`.figures` (headless
pictures).
"""
