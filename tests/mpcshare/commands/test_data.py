"""`mpcshare inspect` and `mpcshare generate`: summaries, one-line errors, the formats, the world family."""

import json

import numpy as np
import pytest

from learning.data import load
from mpcshare.cli import main


def test_inspect_prints_a_summary(data_file, capsys):
    assert main(["inspect", str(data_file)]) == 0
    out = capsys.readouterr().out
    assert "usable" in out and "trials:" in out and "100 Hz" in out and "fork_x" in out
    assert "modes:" in out


def test_inspect_json(data_file, capsys):
    assert main(["inspect", str(data_file), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["n_samples"] == 2 * 3 * 60 * 100 and s["subjects"] == [0, 1]


def test_inspect_names_the_problem_and_fails(tmp_path, capsys):
    bad = tmp_path / "bad.npz"
    obs = np.zeros((10, 2))
    obs[4, 1] = np.nan
    np.savez(bad, obs=obs, act=np.zeros((10, 1)), trial=np.zeros(10, dtype=int), rate_hz=100.0)
    assert main(["inspect", str(bad)]) == 1
    err = capsys.readouterr().err
    assert "bad.npz" in err and "obs" in err and "row 4" in err


def test_inspect_missing_file(tmp_path, capsys):
    assert main(["inspect", str(tmp_path / "nope.npz")]) == 1
    assert "nope.npz" in capsys.readouterr().err


def test_generate_npz_then_inspect(tmp_path, capsys):
    out = tmp_path / "d.npz"
    assert main(["generate", "--subjects", "2", "--minutes", "1", "--seed", "4", "--out", str(out)]) == 0
    d = load(out)
    assert d.subjects == [0, 1] and d.n_samples == 2 * 60 * 100 and d.has_modes
    assert main(["inspect", str(out)]) == 0
    assert "modes:" in capsys.readouterr().out


def test_generate_csv_folder_same_data_as_npz(tmp_path):
    main(["generate", "--subjects", "1", "--minutes", "0.5", "--seed", "1", "--out", str(tmp_path / "a.npz")])
    main(["generate", "--subjects", "1", "--minutes", "0.5", "--seed", "1", "--out", str(tmp_path / "csv")])
    a, b = load(tmp_path / "a.npz"), load(tmp_path / "csv")
    for x, y in zip(a, b):
        np.testing.assert_allclose(x.obs, y.obs, rtol=1e-12, atol=1e-12)
        np.testing.assert_array_equal(x.mode, y.mode)


@pytest.mark.parametrize("args", [["--subjects", "0"], ["--minutes", "-1"], ["--rate", "nan"],
                                  ["--minutes", "ten"]])
def test_generate_rejects_bad_arguments_as_usage_errors(tmp_path, capsys, args):
    with pytest.raises(SystemExit) as e:
        main(["generate", *args, "--out", str(tmp_path / "x.npz")])
    assert e.value.code == 2
    assert f"argument {args[0]}" in capsys.readouterr().err
    assert not (tmp_path / "x.npz").exists()


def test_generate_will_not_replace_a_folder_of_other_files(tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("mine")
    assert main(["generate", "--minutes", "0.1", "--out", str(tmp_path)]) == 1
    assert "cannot write" in capsys.readouterr().err
    assert (tmp_path / "notes.txt").read_text() == "mine"


def test_generate_a_world_of_the_family(tmp_path, capsys) -> None:
    from sim.world_family import world_demonstrations

    out = tmp_path / "w.npz"
    assert main(["generate", "--world", "5", "--trials", "2", "--trial-seconds", "5", "--out", str(out)]) == 0
    assert "world 5: modes cutting (stroke)" in capsys.readouterr().out
    expected, _ = world_demonstrations(5, 2, 5.0)
    np.testing.assert_allclose(load(out).trials[1].act, expected.trials[1].act)
