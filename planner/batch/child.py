"""The process a batch worker runs its tasks in: ``python -m planner.batch.child``.

Once ``planner`` is imported it writes ``{"ready": PID}``; then it reads one task per line
(JSON) on stdin and answers each with one line of JSON (the
record of :func:`~planner.batch.execute.execute`) on the stdout it was started with;
anything else written to stdout (by the planner or a native library) goes to stderr, so
the answer channel stays clean. It lives as long as its worker, with ``planner``
imported once; the worker kills it for a task over its time or memory limit and starts
another for the next task.
"""

from __future__ import annotations

import json
import logging
import os
import sys

from .execute import execute
from .tasks import Task


def main() -> int:
    answers = os.fdopen(os.dup(1), "w", encoding="utf-8")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    logging.basicConfig(level=logging.WARNING, stream=sys.stderr,
                        format="%(levelname)s %(name)s: %(message)s")
    import planner.assembly  # noqa: F401 (imported once, before the first task)
    import planner.io  # noqa: F401
    import planner.planning  # noqa: F401

    answers.write(json.dumps({"ready": os.getpid()}) + "\n")
    answers.flush()
    for line in sys.stdin:
        if not line.strip():
            continue
        record = execute(Task.from_json(json.loads(line)))
        answers.write(json.dumps(record, allow_nan=False) + "\n")
        answers.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
