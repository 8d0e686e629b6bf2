"""Diagnostic studies on the solid references (contact spaces, supported ends)."""
