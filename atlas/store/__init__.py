"""The files: schema, formats (HDF5, Zarr), partial runs, reading and validation."""
