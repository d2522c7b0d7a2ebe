"""Maintainer tools that do not ship in the package (the fault soak of `make faults`)."""
