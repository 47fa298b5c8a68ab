"""xbsm: an xarray-based electro-optical imaging system performance model."""
