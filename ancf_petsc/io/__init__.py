"""Results on disk: ``results`` (results.h5 and summary.json, level by level), ``vtk`` (ParaView
surfaces and contact points), ``restart`` (the exact path state of a run's last level),
``reader`` (a run read back: ``read_results``), ``surface_fields`` (the registry of the surfaces'
point fields) and ``files`` (atomic writes, file-system errors)."""

#: the sub-modules (imported on use: a plain import of the package loads none of them)
__all__ = ["files", "reader", "restart", "results", "surface_fields", "vtk"]
