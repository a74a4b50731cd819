"""The application layer: what the CLI and the REST service call, and nothing else does.

Each function takes and returns plain contract documents (dicts) or the library's own
objects, validates at the edge, picks the default store where the caller gives none, and
never depends on how it was reached. The two doors (``rcsa.cli``, ``service``) import of
rcsa only this layer, the domain-free plumbing of :mod:`rcsa.infra` (job queue, SQLite,
API keys, compute backends), :mod:`rcsa.errors` and :mod:`rcsa._version` (import-linter
contracts ``service-through-app`` and ``cli-through-app``). No module here re-exports what
lives below it: each offers operations of its own (``tests/test_architecture.py`` checks).

Modules: :mod:`.predictions` (one assembly, batches, the example assemblies),
:mod:`.analyses` (lobes, effects, identification, diagnosis), :mod:`.measurements` (the
store as users see it), :mod:`.libraries` (batches and whole tool libraries prepared as
work, stored libraries and their exports), :mod:`.presets` (chatter-safe presets),
:mod:`.jobs` (answer now or queue a job: one decision, one handler), :mod:`.figures` and
:mod:`.exports` (pictures and CSV files), :mod:`.stores` (which store a call uses),
:mod:`.keys` (the key file and key ring of a store), :mod:`.bounds` (the validation bounds
the REST schemas publish), :mod:`.budget` (the compute budget), :mod:`.inputs` (the JSON
decoding policy).
"""
