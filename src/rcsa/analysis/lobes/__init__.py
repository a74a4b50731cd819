"""Stability lobe diagrams for milling: :mod:`.zoa` (zero-order solution), :mod:`.semi_discretization`
(time-periodic, on a :mod:`.modal_model`, period map in :mod:`.monodromy`), :mod:`.request` and
:mod:`.options` (the request body and its method), :mod:`.robust` (depth limits that hold with a
stated confidence over drawn assemblies)."""
