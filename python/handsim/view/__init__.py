"""handsim.view: see a world in 3D.

* :func:`show` / :class:`Viewer`: a live world in the browser (viser), updated after each step;
* ``python -m handsim.view FILE`` / ``--demo``: a recording with a timeline, or the simulated user live;
* :mod:`handsim.view.scene`: the scene description both draw from; :mod:`handsim.view.raster`: offline
  shaded pictures of it (the demo's and the docs'), without a browser or a GPU.

The viewer needs the optional extra (``pip install 'handsim[view]'``); ``import handsim`` never imports this
package, and this package imports viser only when a Viewer is made.
"""
from .scene import Describer, Frame, describe  # noqa: F401
from .raster import Camera, render  # noqa: F401


def show(world, names=None, **kwargs):
    """A :class:`Viewer` of `world`, already showing it; call ``.update()`` after each step."""
    from .viewer import show as _show
    return _show(world, names, **kwargs)


def __getattr__(name):
    if name == "Viewer":
        from .viewer import Viewer
        return Viewer
    raise AttributeError(name)
