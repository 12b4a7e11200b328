"""scatterlab: real-time rendering of inhomogeneous single-scattering media (docs/python.md).

    import scatterlab as sl
    scene = sl.load_scene("data/scenes/glow.json", overrides={"camera.width": 160})
    img, stats = sl.render(scene, method="gradient", backend="cpu")   # float32 (H, W, 3)
    ref, _ = sl.render(scene, method="exact")
    print(sl.compare(img, ref)["rel_l2"])
"""
import os as _os
import sys as _sys

# The interpreter CMake built the extension for (configured by python/CMakeLists.txt). The
# extension is tied to its Python version, and numpy comes from that interpreter's packages:
# another interpreter (a pyenv or virtualenv python first on the PATH) fails to import it.
BUILT_FOR = "@Python3_EXECUTABLE@"
BUILT_FOR_VERSION = "@Python3_VERSION_MAJOR@.@Python3_VERSION_MINOR@"


def _mismatch(why):
    here = "%d.%d" % _sys.version_info[:2]
    return ImportError(
        "scatterlab was built for %s (Python %s), not for this interpreter %s (Python %s): %s; "
        "run it with %s" % (BUILT_FOR, BUILT_FOR_VERSION, _sys.executable, here, why, BUILT_FOR)
    )


def _same_interpreter():
    try:
        return _os.path.realpath(_sys.executable) == _os.path.realpath(BUILT_FOR)
    except OSError:
        return False


if "%d.%d" % _sys.version_info[:2] != BUILT_FOR_VERSION:
    raise _mismatch("the extension module is for another Python version")
try:
    import numpy as _numpy  # noqa: F401  (the extension's arrays; imported lazily by pybind11)
except ImportError as _e:
    raise _mismatch("numpy cannot be imported here (%s)" % _e) from None
try:
    from ._core import (  # noqa: F401
        ConfigError,
        Error,
        GpuError,
        IoError,
        LimitError,
        Renderer,
        Scene,
        __version__,
        compare,
        density_volume,
        list_methods,
        load_scene,
        read_exr,
        render,
        write_exr,
        write_png,
    )
except ImportError as _e:
    if _same_interpreter():
        raise
    raise _mismatch(str(_e)) from _e
