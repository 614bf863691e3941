"""The ablation summary reads each cell's run folder and lays the cells out per study, Real row first."""

from __future__ import annotations

import json

import pytest

from motiondiff.eval.ablation import collect, format_tables, write_table


def _cell(root, name, prediction, representation, backbone, tables, fid, steps):
    run = root / name
    run.mkdir()
    summary = {"fid": [fid, 0.5, 20], "r_precision_top3": [0.5, 0.02, 20], "smoothness": [0.97, 0.001, 20]}
    real = {"fid": [3.0 if representation == "hml263" else 3.1, 0.0, 20], "r_precision_top3": [0.75, 0.02, 20]}
    (run / "metrics.json").write_text(json.dumps({"guidance": 4.0, "summary": summary, "real": real, "wall_s": 60}))
    study = {"cell": name, "prediction": prediction, "representation": representation, "backbone": backbone,
             "tables": tables}  # fmt: skip
    (run / "run.json").write_text(json.dumps({"train_steps": steps, "study": study}))


def test_tables_per_study(tmp_path):
    _cell(tmp_path, "v_jp", "v", "jp", "trans_enc", ["prediction_representation"], 7.25, 1100)
    _cell(tmp_path, "x0_hml263", "x0", "hml263", "trans_enc", ["prediction_representation", "backbone"], 5.5, 1000)
    _cell(tmp_path, "gru_x0_hml263", "x0", "hml263", "gru", ["backbone"], 9.0, 1500)
    (tmp_path / "unfinished").mkdir()  # a cell that died before writing its metrics is left out
    cells = collect(tmp_path)
    assert len(cells) == 3
    text = format_tables(cells)
    pred, backbone = text.split("### Backbone")
    assert "v · jp (1,100 steps)" in pred and "x0 · hml263 (1,000 steps)" in pred and "gru" not in pred
    assert "trans_enc (1,000 steps)" in backbone and "gru (1,500 steps)" in backbone and "v · jp" not in backbone
    assert "| Real |" in pred and "3.000 ± 0.000" in pred  # Real from the cell that reads hml263 natively
    assert "7.250 ± 0.500" in pred and "0.970 ± 0.001" in text  # FID and smoothness with their CIs
    assert (
        "python train.py -m experiment=ablation_bandai 'ablation=glob(*,exclude=[*_rpqjr,*_t10,*_t100,*_token_*])'"
        in text
    )
    path = write_table(tmp_path)
    assert path.read_text() == text and (tmp_path / "ablation.png").stat().st_size > 10_000


def test_no_finished_cell(tmp_path):
    with pytest.raises(FileNotFoundError, match="no finished ablation cell"):
        write_table(tmp_path)
