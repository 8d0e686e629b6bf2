"""The three Achilles subtendons as 3D solids with contact by exact multipliers (docs/solid_contact.md)."""
