"""Distribution over MPI ranks without PETSc: ``layout`` (which rank owns which nodes and elements,
the PETSc numbering), ``partition`` (contiguous blocks per beam or METIS, contact pairs kept
together) and ``launch`` (the environment a launcher gives a process)."""

#: the sub-modules (imported on use: a plain import of the package loads none of them)
__all__ = ["launch", "layout", "partition"]
