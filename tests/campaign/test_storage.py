"""The results directory: atomic chunk files, resume bookkeeping, and refusal of foreign or corrupt
directories (nothing is overwritten). Synthetic chunk tables: no simulation needed here."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from formation_ftc.campaign import CampaignError, CampaignStore, make_plan


def _table(plan, chunk_id):
    ids = plan.chunk(chunk_id).run_ids
    return pd.DataFrame(
        {"run_id": ids, "status": ["ok"] * len(ids), "metric:x": [float(i) for i in ids]}
    )


@pytest.fixture
def plan(tiny):
    return make_plan(tiny(runs=3, chunk_size=2))  # 2 grid points x 2 chunks


def test_new_store_resume_and_results(tmp_path, plan):
    root = tmp_path / "c"
    store = CampaignStore.prepare(root, plan)
    assert store.is_new and not root.exists()  # prepare writes nothing
    store.initialize()
    manifest = json.loads((root / "manifest.json").read_text())
    assert (
        manifest["spec_hash"] == plan.hash and manifest["n_chunks"] == 4 and manifest["n_runs"] == 6
    )
    assert manifest["package_version"] and manifest["swept"] == ["input:controller.kd"]
    store.write_chunk(2, _table(plan, 2))
    store.write_chunk(0, _table(plan, 0))
    assert not [
        p for p in (root / "chunks").iterdir() if p.name.startswith(".")
    ]  # no temporary left
    again = CampaignStore.prepare(root, plan)
    assert not again.is_new and again.finished() == {0, 2}
    with pytest.raises(CampaignError, match="already stored"):
        again.write_chunk(0, _table(plan, 0))
    df = CampaignStore.read(root).load_results()
    assert df["run_id"].tolist() == [0, 1, 3, 4]  # sorted by run id, nothing duplicated


def test_stale_temporary_file_of_a_killed_write_is_discarded(tmp_path, plan):
    root = tmp_path / "c"
    store = CampaignStore.prepare(root, plan)
    store.initialize()
    store.close()
    stale = root / "chunks" / ".chunk-000001.parquet.tmp-12345"
    stale.write_bytes(b"half a parquet file")
    again = CampaignStore.prepare(root, plan)
    assert again.finished() == set() and stale.exists()  # never counted; a scan deletes nothing
    again.initialize()  # only the lock holder removes interrupted writes
    assert not stale.exists()
    again.close()


def test_foreign_directory_is_refused(tmp_path, plan):
    root = tmp_path / "c"
    root.mkdir()
    (root / "thesis.tex").write_text("precious")
    with pytest.raises(CampaignError, match="not a campaign directory; refusing to overwrite"):
        CampaignStore.prepare(root, plan)
    assert (root / "thesis.tex").read_text() == "precious"


def test_other_campaign_is_refused_naming_the_difference(tmp_path, plan, tiny):
    root = tmp_path / "c"
    s = CampaignStore.prepare(root, plan)
    s.initialize()
    s.write_chunk(0, _table(plan, 0))
    other = make_plan(tiny(runs=4, chunk_size=2))
    with pytest.raises(
        CampaignError, match=r"holds another campaign .*campaign.runs: 3 there, 4 here"
    ):
        CampaignStore.prepare(root, other)
    assert CampaignStore.prepare(root, plan).finished() == {0}  # untouched


def test_corrupt_manifest_chunk_and_unknown_files_are_refused(tmp_path, plan):
    root = tmp_path / "c"
    s = CampaignStore.prepare(root, plan)
    s.initialize()
    s.write_chunk(1, _table(plan, 1))
    (root / "chunks" / "chunk-000001.parquet").write_bytes(b"not parquet")
    # a chunk that does not match its checksum is reported and recomputed, never used
    assert CampaignStore.prepare(root, plan).finished() == set()
    with pytest.raises(
        CampaignError, match=r"corrupt chunk file.*chunk-000001.parquet: content does not match"
    ):
        CampaignStore.read(root)
    (root / "chunks" / "chunk-000001.parquet").unlink()
    (root / "chunks" / "notes.txt").write_text("x")
    with pytest.raises(CampaignError, match=r"notes.txt: unknown file"):
        CampaignStore.prepare(root, plan)
    (root / "chunks" / "notes.txt").unlink()
    (root / "chunks" / "chunk-000009.parquet").write_bytes(b"")
    with pytest.raises(CampaignError, match=r"chunk 9 does not exist"):
        CampaignStore.prepare(root, plan)
    (root / "chunks" / "chunk-000009.parquet").unlink()
    # a chunk file holding the wrong runs (copied from another chunk): its checksum does not match
    s2 = CampaignStore.prepare(root, plan)
    s2.write_chunk(0, _table(plan, 0))
    (root / "chunks" / "chunk-000001.parquet").write_bytes(
        (root / "chunks" / "chunk-000000.parquet").read_bytes()
    )
    assert CampaignStore.prepare(root, plan).finished() == {0}
    # ... and with a forged checksum, the run ids still give it away
    m = json.loads((root / "manifest.json").read_text())
    m["chunk_sha256"]["1"] = m["chunk_sha256"]["0"]
    (root / "manifest.json").write_text(json.dumps(m))
    with pytest.raises(CampaignError, match=r"holds runs \[0, 1\].* but chunk 1 is runs 2..2"):
        CampaignStore.prepare(root, plan)
    (root / "chunks" / "chunk-000001.parquet").unlink()
    (root / "manifest.json").write_text("{not json")
    with pytest.raises(CampaignError, match="corrupt campaign manifest"):
        CampaignStore.prepare(root, plan)
    (root / "manifest.json").write_text(json.dumps({"format": "something-else"}))
    with pytest.raises(CampaignError, match="not a formation-ftc campaign manifest"):
        CampaignStore.prepare(root, plan)
    with pytest.raises(CampaignError, match="not a formation-ftc campaign manifest"):
        CampaignStore.read(root)


def test_other_package_version_is_refused(tmp_path, plan):
    root = tmp_path / "c"
    s = CampaignStore.prepare(root, plan)
    s.initialize()
    m = json.loads((root / "manifest.json").read_text())
    m["package_version"] = "0.0.1"
    (root / "manifest.json").write_text(json.dumps(m))
    with pytest.raises(CampaignError, match="written by formation-ftc 0.0.1"):
        CampaignStore.prepare(root, plan)
