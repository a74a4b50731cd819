"""Whole tool libraries as the CLI and the REST service use them: predictions, syncs, exports."""

from __future__ import annotations

from rcsa.libraries.exports import library_hdf5, library_uff_zip
from rcsa.libraries.fusion import library_combinations
from rcsa.libraries.library_prediction import (
    LIBRARY_OPTIONS,
    check_common,
    checked_batch,
    library_request,
    predict_library,
    run_entries,
    run_library_request,
    select_tool_point,
)
from rcsa.libraries.sync import (
    DIRECTORY,
    LIBRARY_ID_PATTERN,
    LibraryStore,
    SyncPlan,
    SyncReport,
    library_id_from_name,
    plan_sync,
    run_sync,
    sync_library,
    sync_request,
)

__all__ = [
    "DIRECTORY",
    "LIBRARY_ID_PATTERN",
    "LIBRARY_OPTIONS",
    "LibraryStore",
    "SyncPlan",
    "SyncReport",
    "check_common",
    "checked_batch",
    "library_combinations",
    "library_hdf5",
    "library_id_from_name",
    "library_request",
    "library_uff_zip",
    "plan_sync",
    "predict_library",
    "run_entries",
    "run_library_request",
    "run_sync",
    "select_tool_point",
    "sync_library",
    "sync_request",
]
