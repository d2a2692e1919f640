"""Build the API reference (HTML, with pdoc) from the docstrings of planner's public API.

``python docs/build_api.py [--out docs/api]`` writes ``index.html`` and ``planner.html``:
every name in ``planner.__all__`` (functions, result classes, errors, settings) with its
signature and docstring, and a search index. It fails (exit 1, one line per problem on
stderr) when a public name does not resolve or has no docstring, or when pdoc warns.
Needs the ``docs`` extra (``pip install -e '.[docs]'``). The output is not committed.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import warnings
from pathlib import Path

DEFAULT_OUT = Path(__file__).resolve().parent / "api"
PACKAGE = "planner"


def public_names(package) -> list[str]:
    """The package's ``__all__``, each name resolved (planner imports them lazily, and
    pdoc documents only what the module already holds)."""
    for name in package.__all__:
        getattr(package, name)
    return list(package.__all__)


def undocumented(package, names: list[str]) -> list[str]:
    """Problems with the public names: those without a docstring of their own."""
    problems = []
    for name in names:
        value = getattr(package, name)
        if not callable(value):
            continue  # an instance (``tol``): documented by its class
        doc = (value.__doc__ or "").strip()
        if not doc or doc.startswith(f"{value.__name__}("):  # a dataclass's generated one
            problems.append(f"{PACKAGE}.{name} has no docstring")
    return problems


def build(out: Path) -> list[str]:
    """Render the reference into ``out``; returns the problems found (empty: success)."""
    import pdoc
    import pdoc.render

    package = importlib.import_module(PACKAGE)
    names = public_names(package)
    problems = undocumented(package, names)
    pdoc.render.configure(docformat="google", show_source=False,
                          footer_text=f"minkplan {package.__version__}")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pdoc.pdoc(PACKAGE, rf"!{PACKAGE}\..*", output_directory=out)
    problems += [f"pdoc: {str(w.message).splitlines()[0]}" for w in caught]
    return problems


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT,
                        help=f"output folder (default: {DEFAULT_OUT})")
    args = parser.parse_args(argv)
    try:
        problems = build(args.out)
    except ImportError as exc:
        sys.stderr.write(f"build_api: {exc}: install the docs extra, pip install -e '.[docs]'\n")
        return 1
    for problem in problems:
        sys.stderr.write(f"build_api: {problem}\n")
    if problems:
        return 1
    sys.stdout.write(f"wrote the API reference to {args.out / 'index.html'}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
