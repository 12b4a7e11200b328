"""scatterlab: real-time rendering of inhomogeneous single-scattering media (docs/python.md).

    import scatterlab as sl
    scene = sl.load_scene("data/scenes/glow.json", overrides={"camera.width": 160})
    img, stats = sl.render(scene, method="gradient", backend="cpu")   # float32 (H, W, 3)
    ref, _ = sl.render(scene, method="exact")
    print(sl.compare(img, ref)["rel_l2"])
"""
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
    load_scene,
    read_exr,
    render,
    write_exr,
    write_png,
)
