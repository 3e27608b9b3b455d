"""What a user asks granchain to do, from a scene to a result: one module per workflow.

Plan a scene (every "auto" value filled, each choice with its reason), run it on a backend, estimate
its errors from companion runs at 2 dt and 4 dt, compare the two backends or two contact laws on
one scene, study accuracy against cost, render a stand-alone deck and collect its results, submit
it to a batch queue, plot a run and load a run directory back. The backends (``granchain.reference``,
``granchain.lammps``) are below this layer; the command line and ``granchain reproduce`` above it.
"""
