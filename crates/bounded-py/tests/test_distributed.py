"""bounded.distributed: a survey's tiles on a Dask cluster give the CLI's outputs, byte for byte."""

import pathlib

import numpy as np
import pytest
from dask.distributed import Client, LocalCluster

import bounded
import bounded.distributed
from conftest import REPO, open_box, run_cli


def write_tiles(directory, xyz, cells):
    """``xyz`` cut into ``cells`` x ``cells`` LAS tiles by x and y; their paths."""
    lo, hi = xyz.min(axis=0), xyz.max(axis=0)
    cell = np.minimum((cells * (xyz[:, :2] - lo[:2]) / (hi[:2] - lo[:2])).astype(int), cells - 1)
    paths = []
    for j in range(cells):
        for i in range(cells):
            path = directory / f"tile{j}{i}.las"
            bounded.write(path, xyz[(cell[:, 0] == i) & (cell[:, 1] == j)])
            paths.append(path)
    return paths


@pytest.fixture(scope="module")
def survey(tmp_path_factory, bounded_bin):
    """A 2 x 2 survey of an open box and the CLI's outputs of it, as PLY."""
    directory = tmp_path_factory.mktemp("survey")
    tiles = write_tiles(directory, open_box(n=6000, size=(8.0, 6.0, 2.0), seed=4), 2)
    done = run_cli(bounded_bin, "detect", *tiles, "-o", directory / "cli", "--format", "ply")
    assert "with halos" in done.stderr, done.stderr
    return tiles, sorted((directory / "cli").iterdir())


def test_two_workers_write_the_clis_bytes(survey, tmp_path):
    tiles, cli = survey
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True) as cluster:
        with Client(cluster) as client:
            outputs = bounded.distributed.detect_tiles(
                tiles, tmp_path / "out", client, format="ply", threads=1
            )
            assert [p.name for p in outputs] == [p.name for p in cli]
            assert all(o.read_bytes() == c.read_bytes() for o, c in zip(outputs, cli))
            # A task run again (a retry) rewrites the same bytes.
            before = [o.read_bytes() for o in outputs]
            again = bounded.distributed.detect_tiles(
                tiles, tmp_path / "out", client, format="ply", threads=1
            )
            assert again == outputs and [o.read_bytes() for o in again] == before
            assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [p.name for p in cli]


def test_without_a_client_a_local_cluster_runs_and_closes(survey, tmp_path):
    tiles, cli = survey
    outputs = bounded.distributed.detect_tiles(tiles, tmp_path / "out", format="ply")
    assert all(o.read_bytes() == c.read_bytes() for o, c in zip(outputs, cli))


def test_one_tile_with_a_small_first_halo_grows_it(survey, tmp_path):
    tiles, cli = survey
    plan = bounded.plan_survey(tiles)
    assert [pathlib.Path(p).name for p, *_ in plan] == [t.name for t in tiles]
    report = bounded.detect_tile(plan, 3, tmp_path / "tile11.ply", radius=0.01)
    assert report["attempts"] > 1 and report["radius"] > 0.01, report
    assert (tmp_path / "tile11.ply").read_bytes() == cli[3].read_bytes()
    with pytest.raises(ValueError, match="no tile 4"):
        bounded.detect_tile(plan, 4, tmp_path / "none.ply")


def test_a_tile_by_the_embedded_band_model_is_the_band_file_s(survey, tmp_path):
    tiles, cli = survey
    plan = bounded.plan_survey(tiles)
    band_file = REPO / "crates" / "bounded-nn" / "models" / "band.bmodel"
    bounded.detect_tile(plan, 1, tmp_path / "by_name.ply", embedded="band")
    bounded.detect_tile(plan, 1, tmp_path / "by_file.ply", model=band_file)
    by_name = (tmp_path / "by_name.ply").read_bytes()
    assert by_name == (tmp_path / "by_file.ply").read_bytes()
    assert by_name != cli[1].read_bytes()
    with pytest.raises(ValueError, match="not both"):
        bounded.detect_tile(plan, 1, tmp_path / "x.ply", model=band_file, embedded="band")



def test_one_large_file_in_blocks_is_the_file_labelled_whole(tmp_path):
    path = tmp_path / "box.laz"
    bounded.write(path, open_box(n=9000, size=(8.0, 6.0, 2.0), seed=5))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True) as cluster:
        with Client(cluster) as client:
            whole = bounded.distributed.detect_tiles([path], tmp_path / "whole", client)
            blocks = bounded.distributed.detect_tiles(
                [path], tmp_path / "blocks", client, block_points=2000, threads=1
            )
    (xyz, fields), (want_xyz, want) = bounded.read(blocks[0]), bounded.read(whole[0])
    assert np.array_equal(xyz, want_xyz) and fields.keys() == want.keys()
    assert all(np.array_equal(fields[k], want[k]) for k in want)
    plan = bounded.plan_survey([path])
    report = bounded.detect_tile(plan, 0, tmp_path / "b.laz", block_points=2000)
    assert report["halo"] > 0 and report["points"] == 9000, report
    with pytest.raises(ValueError, match="write .las or .laz"):
        bounded.detect_tile(plan, 0, tmp_path / "b.ply", block_points=2000)
