"""minkplan's PEP 517 build backend: maturin's, after checking that cargo is on PATH.

minkplan compiles a Rust extension (``minkowski_core``), so every hook that builds or
describes the package needs cargo. maturin's own hooks, when cargo is missing, ask for a
helper that downloads a Rust toolchain, and without network that ends in a long
traceback. Here a missing cargo ends the hook at once with one line on stderr that says
what to install (exit status 1); everything else is delegated to maturin unchanged.
``pyproject.toml`` names this module with ``backend-path = ["build_backend"]``.
"""

from __future__ import annotations

import shutil
import sys
from collections.abc import Callable
from typing import Any

NO_CARGO = ("minkplan builds a Rust extension and cargo is not on PATH: install a Rust "
            "toolchain (https://rustup.rs, or your system's cargo package) and retry, or "
            "install a prebuilt minkplan wheel (pip install minkplan-*.whl)")
"""The one line a build without cargo ends with."""


def _require_cargo() -> None:
    if shutil.which("cargo") is None:
        sys.stderr.write(NO_CARGO + "\n")
        sys.stderr.flush()
        raise SystemExit(1)


def _maturin_hook(name: str) -> Callable[..., Any]:
    """maturin's hook ``name``, run only when cargo is on PATH."""

    def hook(*args: Any, **kwargs: Any) -> Any:
        _require_cargo()
        import maturin

        return getattr(maturin, name)(*args, **kwargs)

    hook.__name__ = name
    hook.__doc__ = f"maturin's ``{name}``, after checking that cargo is on PATH."
    return hook


get_requires_for_build_wheel = _maturin_hook("get_requires_for_build_wheel")
get_requires_for_build_editable = _maturin_hook("get_requires_for_build_editable")
get_requires_for_build_sdist = _maturin_hook("get_requires_for_build_sdist")
prepare_metadata_for_build_wheel = _maturin_hook("prepare_metadata_for_build_wheel")
prepare_metadata_for_build_editable = _maturin_hook("prepare_metadata_for_build_editable")
build_wheel = _maturin_hook("build_wheel")
build_editable = _maturin_hook("build_editable")
build_sdist = _maturin_hook("build_sdist")
