"""Order of the gallery's examples (sphinx-gallery ``within_subsection_order``)."""

from __future__ import annotations

#: From one flow to sweeps; examples not listed come after, by file name.
ORDER = (
    "plot_steady_profiles.py",
    "plot_flux_density.py",
    "plot_stability_diagram.py",
    "plot_reduced_waves.py",
    "plot_dns_density_wave.py",
    "plot_custom_closure.py",
    "plot_read_sweep.py",
    "plot_dask_sweep.py",
)


class GalleryOrder:
    """Sort key: the position in :data:`ORDER`, then the file name."""

    def __init__(self, src_dir: str):
        self.src_dir = src_dir

    def __call__(self, filename: str) -> tuple[int, str]:
        return (ORDER.index(filename) if filename in ORDER else len(ORDER), filename)

    def __repr__(self) -> str:
        return "GalleryOrder"
