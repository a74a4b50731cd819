"""rcsa: tool-point frequency response functions of spindle–holder–tool assemblies.

Exact Timoshenko receptance coupling (Budak, Ertürk & Özgüven, CIRP Annals 2006), measured
spindle FRFs, and a diagnosis of the gap between model and measurement.
"""

from __future__ import annotations

__version__ = "0.1.0"
