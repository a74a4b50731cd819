"""Measured spindles: the HDF5 store, importers of foreign FRF files, and hybrid coupling.

Packages and modules: :mod:`.store` (immutable per-measurement HDF5 files and their
catalogue), :mod:`.importers` (UFF 58, CSV, CutPro, contract JSON, raw tap tests),
:mod:`.artifact_identification` (the spindle's 2×2 receptance from artifact FRFs),
:mod:`.hybrid` (a stored measurement → the base receptance holder and tool couple to).
"""
