"""petsc"""
