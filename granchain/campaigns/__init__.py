"""Campaigns: sweeps and searches over scenes, cached in a signac workspace, run on Dask."""
