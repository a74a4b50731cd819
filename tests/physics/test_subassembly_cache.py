"""The one subassembly cache: read-only results, found by identity or by value, one LRU policy."""

from __future__ import annotations

import numpy as np
import pytest

from rcsa.model.assembly import build_model
from rcsa.model.contract import parse_assembly
from rcsa.model.reference import ra1_spindle_receptance
from rcsa.physics.chain import Spring
from rcsa.physics.elimination import march, static_condense
from rcsa.physics.subassembly_cache import LruStore, SubassemblyCache
from rcsa.reference import ra1
from tests.helpers import RTOL_ALGEBRA, assert_receptance_close

GRID = {"start_hz": 50.0, "stop_hz": 5000.0, "step_hz": 50.0}
OMEGA = 2 * np.pi * np.arange(50.0, 5001.0, 50.0)


def _model(stickout_m=0.074):
    doc = ra1(GRID)
    doc["tool"]["stickout_m"] = stickout_m
    return build_model(parse_assembly(doc))


def test_what_it_hands_out_is_read_only():
    cache = SubassemblyCache(OMEGA, max_beams=16)
    prefix = _model().to_holder_tip()
    state = cache.condensed((prefix,))
    for array in (state.stiffness, *state.sym, cache.static(prefix), cache.omega_rad_s,
                  *cache.grid.beam_terms(prefix[-1])):
        assert not array.flags.writeable
        with pytest.raises(ValueError, match="read-only"):
            array[..., 0] = 0.0
    # and what it hands out is right: the chain's march (item by item on the caching grid)
    assert_receptance_close(state.stiffness, march(prefix, OMEGA)[0], RTOL_ALGEBRA)
    np.testing.assert_array_equal(SubassemblyCache(OMEGA).condensed((prefix,)).stiffness, march(prefix, OMEGA)[0])
    np.testing.assert_array_equal(cache.static(prefix), static_condense(prefix))


def test_equal_chains_built_apart_share_one_condensation_and_the_same_objects_are_found_by_identity():
    cache = SubassemblyCache(OMEGA)
    a, b = _model(0.10).to_holder_tip(), _model(0.10).to_holder_tip()
    assert a == b and a is not b
    first = cache.condensed((a,))
    assert cache.condensed((b,)) is first and cache.condensed((a,)) is first
    assert len(cache) == 1
    other = _model(0.12).to_holder_tip()  # less of the shank inside: another holder chain
    assert cache.condensed((other,)) is not first and len(cache) == 2


def test_the_least_recently_used_state_goes_first_and_takes_its_identity_key_along():
    cache = SubassemblyCache(OMEGA, max_states=2)
    chains = [_model(s).to_holder_tip() for s in (0.10, 0.11, 0.12)]  # shank partly in the 80 mm holder
    s0, s1 = cache.condensed((chains[0],)), cache.condensed((chains[1],))
    assert cache.condensed((chains[0],)) is s0          # used: now the most recent
    cache.condensed((chains[2],))                       # evicts chains[1]
    assert cache.condensed((chains[0],)) is s0
    again = cache.condensed((chains[1],))
    assert again is not s1 and np.array_equal(again.stiffness, s1.stiffness)
    assert len(cache) == 2 and len(cache._by_value) <= 2


def test_a_measured_base_is_absorbed_never_inverted_and_keyed_by_identity():
    model = _model()
    base = ra1_spindle_receptance(GRID).values
    cache = SubassemblyCache(OMEGA, base)
    joint_only = (Spring(3.05e7, 365.0, 1.5e6, 40.0),)
    state = cache.condensed((joint_only,))              # no beam yet: still a receptance
    assert state.stiffness is None and not state.compliance.flags.writeable
    holder = model.to_holder_tip()[len(model.spindle):]
    expected = march(holder, OMEGA, start_compliance=base)[0]
    assert_receptance_close(cache.stiffness(holder), expected, RTOL_ALGEBRA)
    other = base.copy()                                 # another draw of the spindle: its own key
    assert cache.condensed((holder,), other) is not cache.condensed((holder,))


def test_the_lru_store_keeps_at_most_its_size():
    dropped = []
    lru = LruStore(3, on_evict=lambda key, value: dropped.append(key))
    for k in range(6):
        lru.get(k, lambda k=k: k * k)
    assert len(lru) == 3 and dropped == [0, 1, 2] and lru.peek(5) == 25
    assert LruStore(0).get("x", lambda: 1) == 1 and len(LruStore(0)) == 0


def test_the_lru_store_makes_a_missing_value_outside_its_lock():
    """A long ``make()`` does not block other threads' reads of the store (here one reads it
    while ``make`` waits for it); ``clear`` empties it."""
    import threading

    lru = LruStore(4)
    lru.put("kept", 1)
    seen = []

    def make():
        reader = threading.Thread(target=lambda: seen.append(lru.peek("kept")))
        reader.start()
        reader.join(timeout=60)  # a deadlock guard, not a timing: the reader must have finished
        return 2

    assert lru.get("new", make) == 2 and seen == [1]
    lru.clear()
    assert len(lru) == 0 and lru.peek("kept") is None


def test_src_has_one_eviction_policy():
    """No bounded cache in src/ but LruStore: no functools.lru_cache, cachetools, or hand-written
    OrderedDict LRU (``functools.cache`` of a single value evicts nothing and is allowed)."""
    import re

    from tests.helpers import REPO

    home = REPO / "src" / "rcsa" / "physics" / "subassembly_cache.py"
    pattern = re.compile(r"\blru_cache\b|\bcachetools\b|\bOrderedDict\b|\bLRUCache\b|\.popitem\(last=False\)")
    found = [f"{p.relative_to(REPO)}:{n}: {line.strip()}"
             for p in sorted((REPO / "src").rglob("*.py")) if p != home
             for n, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1) if pattern.search(line)]
    found += [f"service: {p}" for p in sorted((REPO / "service").rglob("*.py"))
              if pattern.search(p.read_text(encoding="utf-8"))]
    assert not found, "\n".join(found)
