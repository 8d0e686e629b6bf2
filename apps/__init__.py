"""Command-line programs over the ancf_petsc library."""
