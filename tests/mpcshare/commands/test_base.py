"""The command line's error messages, one test per message a person meets (issue: "What a person sees")."""

import argparse

import pytest

from learning.data import save
from mpcshare.cli import COMMANDS, build_parser, main
from sim.demonstrator import GeneratorConfig, generate_demonstrations


@pytest.fixture(scope="module")
def small_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("data") / "demos.npz"
    save(generate_demonstrations(1, 0.2, seed=0, config=GeneratorConfig(trial_minutes=0.1)), path)
    return path


def test_unknown_option_shows_the_subcommands_usage(small_file, tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        main(["train", str(small_file), "--out", str(tmp_path / "m"), "--bogus"])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert "usage: mpcshare train" in err and "--percentile" in err
    assert "unrecognized arguments: --bogus" in err


@pytest.mark.parametrize("command,option,value,words", [
    ("train", "--percentile", "abc", "a number from 0 to 100"),
    ("train", "--percentile", "101", "a number from 0 to 100"),
    ("tune", "--betas", "2", "a number from 0 to 1"),
    ("tune", "--percentiles", "0", "above 0 and at most 100"),
])
def test_ranges_are_named(small_file, tmp_path, capsys, command, option, value, words):
    with pytest.raises(SystemExit) as e:
        main([command, str(small_file), "--out", str(tmp_path / "o"), option, value])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert words in err and repr(value) in err


def test_a_missing_file_is_named_once(tmp_path, capsys):
    missing = tmp_path / "nope.npz"
    assert main(["inspect", str(missing)]) == 1
    err = capsys.readouterr().err
    assert err.count(str(missing)) == 1 and "no such file" in err


def test_a_corrupted_file_is_called_corrupted(small_file, tmp_path, capsys):
    data = bytearray(small_file.read_bytes())
    data[len(data) // 3] ^= 0xFF  # inside the first array's bytes: its CRC-32 no longer matches
    bad = tmp_path / "bad.npz"
    bad.write_bytes(bytes(data))
    assert main(["inspect", str(bad)]) == 1
    err = capsys.readouterr().err
    assert "corrupted" in err and "pickle" not in err and err.count(str(bad)) == 1


def test_top_level_help_lists_every_command():
    text = build_parser().format_help()
    description = text.split("positional arguments")[0]
    for c in COMMANDS:
        assert c.name in description, c.name


def test_sim_help_names_the_runs_it_runs_by_default():
    from mpcshare.evaluation import DEFAULT_RUNS

    sim = next(c for c in COMMANDS if c.name == "sim")
    p = argparse.ArgumentParser()
    sim.add_arguments(p)
    text = " ".join(p.format_help().split())
    names = [r.name for r in DEFAULT_RUNS]
    assert f"default: {len(names)}: {', '.join(names)}; also qp_blend" in text  # a candidate runs when named
    assert p.parse_args(["--model", "m", "--out", "o"]).runs == names
    assert p.parse_args(["--model", "m", "--out", "o", "--runs", "qp_blend"]).runs == ["qp_blend"]


@pytest.mark.parametrize("argv", [
    ["analyze", "{missing}", "--out", "{out}"],
    ["train", "{missing}", "--out", "{out}"],
    ["train", "{missing}", "--sweep", "--out", "{out}"],
    ["sim", "--model", "{missing}", "--out", "{out}"],
    ["tune", "{missing}", "--out", "{out}"],
    ["import", "{missing}", "--mapping", "{missing}", "--out", "{out}/data.npz"],
    ["generate", "--single-regime", "--world", "3", "--out", "{out}/data.npz"],
], ids=lambda argv: " ".join(argv[:3]))
def test_a_failed_command_leaves_no_empty_output_folder(tmp_path, capsys, argv):
    out = tmp_path / "new" / "out"
    args = [a.format(missing=tmp_path / "nonexistent", out=out) for a in argv]
    assert main(args) == 1
    assert capsys.readouterr().err.startswith(f"mpcshare {argv[0]}: ")
    assert not (tmp_path / "new").exists()


def test_a_failed_demo_leaves_no_empty_output_folder_but_keeps_a_users_folder(tmp_path, capsys, monkeypatch):
    import mpcshare.commands.demo as demo
    from mpcshare.commands.base import CommandError

    def fail(*args, **kwargs):
        raise CommandError("cannot generate (a stand-in failure)")

    monkeypatch.setattr(demo, "generate_demonstrations", fail)
    out = tmp_path / "new" / "demo"
    assert main(["demo", "--out", str(out)]) == 1
    assert not (tmp_path / "new").exists()
    mine = tmp_path / "mine"
    mine.mkdir()
    assert main(["demo", "--out", str(mine)]) == 1
    assert mine.is_dir()  # a folder the user made is never removed
