"""Campaigns: sweeps and searches over scenes, cached in a signac workspace, run on Dask.

A campaign file names a base scene and what varies over it (docs/campaigns.md). Every point is a
validated scene, run as ``granchain run`` would run it into its own job directory of the workspace;
the campaign table is read back from those run directories, so an interrupted campaign resumes with
what is missing.

The package's modules, bottom up: ``expr`` (the [derive] expressions, read without eval),
``model`` (the validated campaign and the points it makes), ``cluster_settings`` and ``cluster``
(worker jobs on a batch queue), ``spec`` (reading a campaign file), ``workspace`` (the signac
workspace and when a point counts as complete), ``point_task`` (one point in a worker),
``campaign_progress``, ``dask_executor`` and ``execute`` (running the points on Dask), ``search``
(the search kind's bisections), ``table`` and ``plot`` (the table and its figures) and ``api`` (run
a campaign, load its table).
"""
