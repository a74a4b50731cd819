"""Writer process for the crash and concurrency tests.

    python _writer.py STORE LOG SEED0 COUNT DELETE_EVERY

Puts COUNT measurements ``make_measurement(SEED0 + k)``; after each ``put`` returns it
appends ``put <id> <seed>`` to LOG (flushed and fsynced), and every DELETE_EVERY-th one it
deletes again, logging ``deleting <id>`` before and ``del <id>`` after ``delete``. The parent kills it at
random moments with SIGKILL.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _factory import make_measurement  # noqa: E402

from rcsa.measured.store import MeasurementStore  # noqa: E402


def main() -> None:
    store_path, log_path, seed0, count, delete_every = sys.argv[1:6]
    store = MeasurementStore(store_path)
    with open(log_path, "a", encoding="utf-8") as log:

        def note(line: str) -> None:
            log.write(line + "\n")
            log.flush()
            os.fsync(log.fileno())

        note("ready")
        for k in range(int(count)):
            seed = int(seed0) + k
            mid = store.put(make_measurement(seed))
            note(f"put {mid} {seed}")
            if int(delete_every) and k % int(delete_every) == int(delete_every) - 1:
                note(f"deleting {mid}")
                store.delete(mid)
                note(f"del {mid}")


if __name__ == "__main__":
    main()
