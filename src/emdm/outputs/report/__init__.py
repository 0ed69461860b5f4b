"""``emdm report``: the whole study of the brief in one command, as a paper, a pitch and a page.

The report runs every experiment of the brief (closed loops, evidence runs, solver labs, Pareto
sweeps, figures, animations), writes the records to ``data/``, then renders from those files
only: ``paper/paper.tex`` (IEEEtran, two columns, at most four pages), ``paper/pitch.tex``
(Beamer, 16:9) and ``index.html``, and compiles the LaTeX when ``pdflatex`` is installed.

Modules: :mod:`.config` (what runs), :mod:`.jobs` (the work and :func:`build_report`),
:mod:`.explain` (events detected in the records), :mod:`.findings` and :mod:`.pitch` (the
sentences), :mod:`.tables` (column specifications), :mod:`.trace` (traced numbers),
:mod:`.document` (the document model), :mod:`.render` (templates and compilation).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .trace import format_value


def build_report(out: Path, **kwargs: Any) -> dict[str, Any]:
    """Run the whole study and write it into ``out``; see :func:`.jobs.build_report`."""
    from .jobs import build_report as _build

    return _build(out, **kwargs)


__all__ = ["build_report", "format_value"]
