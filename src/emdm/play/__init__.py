"""``emdm play``: the live playground in the browser (see docs/playground.md).

:mod:`emdm.play.logic` computes everything the page shows and needs no browser library;
:mod:`emdm.play.page` draws it with Bokeh (the ``play`` extra) and :mod:`emdm.play.server` serves it.
"""

from __future__ import annotations

import warnings

from ..core.loading import PLANAR_PRESETS, load_scenario
from ..core.scenario import Scenario
from ..errors import EmdmError


def serve(scenario: Scenario, *, port: int = 5006, open_browser: bool = True) -> int:
    """Serve the playground of ``scenario`` on 127.0.0.1:``port`` (0: any free port) until Ctrl-C
    or SIGTERM; the presets are in the page's menu too. Returns the exit status (0).

    Raises :class:`~emdm.errors.EmdmError` for a bad port or when Bokeh is not installed.
    """
    if not 0 <= port <= 65535:
        raise EmdmError(f"--port must be 0 to 65535, got {port}")
    if scenario.spatial:
        raise EmdmError(
            f"{scenario.name} is a spatial arm; the playground takes planar arms only "
            "(try emdm animate or emdm plot for spatial runs)"
        )
    try:
        from .server import serve as run
    except ImportError as exc:
        raise EmdmError(f"emdm play needs Bokeh: pip install 'emdm[play]' ({exc})") from None
    bases = {scenario.name: scenario}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name in PLANAR_PRESETS:
            bases.setdefault(name, load_scenario(name))
    return run(bases, port=port, open_browser=open_browser)


__all__ = ["serve"]
