"""A survey's tiles labelled on Dask: one task per tile, each with its halo.

``detect_tiles`` plans the tiles from the files (``bounded.plan_survey``: LAS and LAZ headers,
one read of other formats), submits one ``bounded.detect_tile`` task per tile to a
``dask.distributed`` client and waits for them. Every task reads its tile and, read-only,
the points of the neighbouring files within its halo, proves per point that the halo
sufficed (growing it where it did not), and writes its output atomically; so the outputs
are those of ``bounded detect`` on all the files, bit for bit, and a task that is run again
(its worker died, say) rewrites the same bytes. Dask schedules, retries and moves the
tasks; nothing here does.
"""

import os
import pathlib

import bounded


def _run_tile(plan, tile, output, options):
    """One task: tile ``tile`` of ``plan`` into ``output``."""
    return bounded.detect_tile(plan, tile, output, **options)


def detect_tiles(inputs, output_dir, client=None, *, format=None, **options):
    """Labels the files ``inputs`` (the tiles of a survey) as one survey on Dask and writes
    each one's result to ``output_dir`` under its own file name (with the extension
    ``format``, such as ``"ply"``, when given), as ``bounded detect INPUTS -o OUTPUT_DIR``
    does. Returns the output paths, in input order.

    ``client`` is a ``dask.distributed.Client``; without one, a ``LocalCluster`` is started
    and closed afterwards. ``options`` are ``bounded.detect_tile``'s: ``model`` (a model file's
    path) or ``embedded`` (``"row"`` or ``"band"``), ``scales``, ``sensitivity``, ``fast``, ``drop_non_finite``, ``radius``,
    ``block_points`` (a single LAS or LAZ file of more points is one task that labels it in
    spatial blocks) and ``threads`` (per task).
    """
    inputs = [pathlib.Path(p) for p in inputs]
    output_dir = pathlib.Path(output_dir)
    outputs = []
    for path in inputs:
        out = output_dir / path.name
        if format is not None:
            out = out.with_suffix("." + format.lstrip("."))
        if out in outputs:
            raise ValueError(f"{path}: another input is written to {out} too; rename one")
        outputs.append(out)
    plan = bounded.plan_survey(inputs, drop_non_finite=options.get("drop_non_finite", False))
    os.makedirs(output_dir, exist_ok=True)
    own = client is None
    if own:
        from dask.distributed import Client, LocalCluster

        cluster = LocalCluster(processes=True, threads_per_worker=1)
        client = Client(cluster)
    try:
        futures = [
            client.submit(_run_tile, plan, tile, str(out), options, pure=False)
            for tile, out in enumerate(outputs)
        ]
        client.gather(futures)
    finally:
        if own:
            client.close()
            cluster.close()
    return outputs
