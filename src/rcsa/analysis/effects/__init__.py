"""Effect analysis: which bearing, joint or tool parameter moves which mode, and how much.

Modules: :mod:`.sensitivities` (the analysis and its request: normalised sensitivities
d ln(feature)/d ln(parameter) by central differences of the exact model),
:mod:`.measured_spindle` (the same on a measured spindle, modes from the modal fit),
:mod:`.mode_features` (natural frequency, damped peak and damping ratio of every mode of an
exact model; also used by the joint identification and the lobes' modal model),
:mod:`.report` (:class:`~.report.EffectReport`, the result; its heat map is
:func:`rcsa.analysis.figures.effects_figure`, with the other pictures).
"""
