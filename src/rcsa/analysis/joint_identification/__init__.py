"""Joint identification from measured tool-point FRFs.

Modules: :mod:`.request` (validation), :mod:`.measured_peaks` (what is read from a tap
test), :mod:`.locate` (which mode informs which joint), :mod:`.identify` (the fit).
"""
