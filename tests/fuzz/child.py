"""The fuzz runner's child: ``python tests/fuzz/child.py``. It imports ``planner`` once,
writes ``{"ready": PID}``, then for each line ``{"folder": F, "argv": [...]}`` runs
``minkplan *argv`` in ``F`` (``planner.cli.main``, in this process) with file descriptors
1 and 2 sent to ``F/stdout.txt`` and ``F/stderr.txt`` (native writes included), and
answers ``{"code": EXIT}`` -- or ``{"code": null, "escaped": "..."}`` when an exception
got past ``main`` (a bug in the CLI's own error handling)."""

from __future__ import annotations

import json
import os
import sys
import traceback


def _run(folder: str, argv: list[str]) -> dict:
    from planner.cli import main

    os.chdir(folder)
    saved = os.dup(1), os.dup(2)
    with open("stdout.txt", "wb") as out, open("stderr.txt", "wb") as err:
        os.dup2(out.fileno(), 1)
        os.dup2(err.fileno(), 2)
        try:
            code: int | None = main(argv)
            escaped = None
        except SystemExit as exit_:
            code, escaped = (exit_.code if isinstance(exit_.code, int) else 2), None
        except BaseException:  # noqa: BLE001 (what escapes main is the finding)
            code, escaped = None, traceback.format_exc()
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])
    return {"code": code, "escaped": escaped}


def main() -> int:
    answers = os.fdopen(os.dup(1), "w", encoding="utf-8")
    import planner.cli  # noqa: F401 (imported once, before the first case)
    import planner.planning  # noqa: F401

    answers.write(json.dumps({"ready": os.getpid()}) + "\n")
    answers.flush()
    for line in sys.stdin:
        request = json.loads(line)
        answers.write(json.dumps(_run(request["folder"], request["argv"])) + "\n")
        answers.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
