"""``emdm play``: the live playground in the browser (see docs/playground.md).

A planar arm: :mod:`emdm.play.logic` computes everything the page shows and needs no browser
library; :mod:`emdm.play.page` draws it with Bokeh (the ``play`` extra) and
:mod:`emdm.play.server` serves it. A spatial arm (``panda``, ``ur5``, a URDF file): the 3-D page,
computed by :mod:`emdm.play.scene3d` and drawn and served by :mod:`emdm.play.spatial` with viser
(the ``play3d`` extra).
"""

from __future__ import annotations

import warnings

from ..core.loading import PLANAR_PRESETS, PRESETS, load_scenario
from ..core.scenario import Scenario
from ..errors import EmdmError


def serve(scenario: Scenario, *, port: int = 5006, open_browser: bool = True) -> int:
    """Serve the playground of ``scenario`` on 127.0.0.1:``port`` (0: any free port) until Ctrl-C
    or SIGTERM; the presets of the same kind (planar or spatial) are in the page's menu too.
    A planar arm gets the Bokeh page, a spatial one the 3-D page. Returns the exit status (0).

    Raises :class:`~emdm.errors.EmdmError` for a bad port or when the page's library (Bokeh,
    or viser for a spatial arm) is not installed.
    """
    if not 0 <= port <= 65535:
        raise EmdmError(f"--port must be 0 to 65535, got {port}")
    if scenario.spatial:
        return _serve_spatial(scenario, port, open_browser)
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


def _serve_spatial(scenario: Scenario, port: int, open_browser: bool) -> int:
    try:
        from .spatial import serve as run
    except ImportError as exc:
        raise EmdmError(
            f"{scenario.name} is a spatial arm, and the 3-D playground needs viser: "
            f"pip install 'emdm[play3d]' ({exc})"
        ) from None
    bases = {scenario.name: scenario}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name in PRESETS:
            if name not in bases:
                preset = load_scenario(name)
                if preset.spatial:
                    bases[name] = preset
    return run(bases, port=port, open_browser=open_browser)


__all__ = ["serve"]
