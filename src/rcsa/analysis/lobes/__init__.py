"""Stability lobe diagrams for milling: :mod:`.zoa` (zero-order solution), :mod:`.request`,
:mod:`.robust` (depth limits that hold with a stated confidence over drawn assemblies)."""
