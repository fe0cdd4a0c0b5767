"""qnav_plot.py: the one style of the plots a person reads (imported by qnavd_report.py, map_plot.py,
route_plots.py, vo_plot.py; Debian's python3-matplotlib, run with /usr/bin/python3). The tool's own
PNG rasters (waterfalls, tiles) are drawn by firmware/tools/raster_plot.hpp to the same rules:

- axes say their quantity and unit ("east m"), ticks carry values;
- a legend sits outside the axes (right of them, or below), so it never hides data;
- a plan view (north up) carries a north arrow beside the axes (its ticks in metres are its scale);
- where colour means a value (belief, intensity), a colour bar with its label.
"""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402,F401  (re-exported: `from qnav_plot import plt`)
from matplotlib.ticker import MaxNLocator  # noqa: E402


def legend_outside(ax, where="right", **kw):
    """The legend beside the axes (right) or under them (below): never over the data."""
    kw.setdefault("fontsize", 8)
    if where == "below":
        return ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), borderaxespad=0.0, ncol=kw.pop("ncol", 3), **kw)
    return ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, **kw)


def axes_labels(ax, xlabel, ylabel, grid=True, integer_x=False):
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if integer_x:
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    if grid:
        ax.grid(True, alpha=0.3)


def north_arrow(ax, x=1.05, y=0.02):
    """An arrow pointing up (north), N at its tip, just right of the axes' lower corner (outside the data)."""
    ax.annotate("", xy=(x, y + 0.13), xytext=(x, y), xycoords="axes fraction", textcoords="axes fraction",
                annotation_clip=False, arrowprops=dict(arrowstyle="-|>", color="k", lw=1.5))
    ax.text(x, y + 0.14, "N", transform=ax.transAxes, ha="center", va="bottom", fontsize=10, fontweight="bold", clip_on=False)


def colour_bar(fig, mappable, ax, label, cax=None):
    """A colour bar with its label: beside ax (taking its room), or in cax when given."""
    cb = fig.colorbar(mappable, cax=cax) if cax is not None else fig.colorbar(mappable, ax=ax)
    cb.set_label(label)
    return cb
