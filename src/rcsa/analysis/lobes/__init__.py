"""Stability lobe diagrams for milling: :mod:`.zoa` (zero-order solution), :mod:`.request`."""
