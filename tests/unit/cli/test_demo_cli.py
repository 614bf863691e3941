"""`motiondiff-demo`'s options: local only and no share link by default; `--name value` and `name=value` alike."""

from __future__ import annotations

import pytest

from motiondiff.cli.demo import main, parse_args


def test_defaults_stay_on_this_machine():
    args = parse_args([])
    assert (args.host, args.port, args.share, args.guided, args.model) == ("127.0.0.1", 7860, False, None, None)


def test_both_option_styles():
    args = parse_args(["guided=run/last.ckpt", "--port", "8000", "share=true", "local_model=action", "--host=0.0.0.0"])
    assert (args.guided, args.port, args.share, args.local_model, args.host) == ("run/last.ckpt", 8000, True, "action",
                                                                                  "0.0.0.0")  # fmt: skip
    assert parse_args(["share=false"]).share is False


def test_a_missing_guided_checkpoint_is_one_error_line(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        main([f"guided={tmp_path / 'none.ckpt'}"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("error: no GuidedMotion checkpoint") and "Traceback" not in err


def test_an_install_without_gradio_names_the_extra_to_install(monkeypatch, capsys):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "gradio" else real(name, *a))
    with pytest.raises(SystemExit) as exit_:
        main([])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.count("error:") == 1 and "pip install 'motiondiff[demo]'" in err
