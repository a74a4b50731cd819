"""The physics core: exact beam segments, chains, the elimination solver, natural frequencies.

numpy and scipy only. Modules: :mod:`.materials`, :mod:`.sections` (cross-sections reduced to
EI, κGA, ρA, ρI), :mod:`.segments` (exact Timoshenko segment receptances and stiffness),
:mod:`.chain` (beams, joints and grounded attachments; each owns its elimination step),
:mod:`.elimination` (the production solver), :mod:`.natural_frequencies` (Wittrick–Williams),
:mod:`.stacking` (many tools as one chain), :mod:`.coupling` (receptance coupling functions),
:mod:`.algebra2x2` (closed-form 2×2 stacks), :mod:`.receptance` (frequency-first FRF types),
:mod:`.arrays` (array type aliases).
"""
