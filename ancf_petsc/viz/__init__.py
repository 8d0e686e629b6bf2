"""Figures from run outputs (matplotlib, Agg canvas only; no PETSc): shaded 3D renders of the
surfaces (render.py), line charts of results (figures.py), a contact run's force and interface
charts (interface_charts.py), a load history's figure (history.py), the interface study's chart
(law_charts.py) and study charts (charts.py)."""
from .figures import (counted_points, curve_from_summary, interface_labels, plot_convergence,
                      plot_load_elongation, plot_slip, read_csv_table, save_figure)
from .history import plot_history
from .interface_charts import plot_force_and_differences
from .law_charts import plot_law_differences
from .render import render_pair, render_surfaces
from .surface_mesh import SurfaceMesh, field_values, read_surface

__all__ = ["SurfaceMesh", "counted_points", "curve_from_summary", "field_values", "interface_labels",
           "plot_convergence", "plot_force_and_differences", "plot_history", "plot_law_differences", "plot_load_elongation", "plot_slip",
           "read_csv_table", "read_surface", "render_pair", "render_surfaces", "save_figure"]
