"""`mpcshare train`: what it writes to a pipe."""

from mpcshare.cli import main


def test_train_output_captured_to_a_pipe_holds_lines_not_progress_bars(data_file, tmp_path, capsys):
    """Progress bars draw on a terminal only (learning.progress): a redirected log gets no carriage return."""
    assert main(["train", str(data_file), "--out", str(tmp_path / "model"), "--epochs", "2",
                 "--no-rule-choice"]) == 0
    said = capsys.readouterr()
    assert said.out.strip() and "\r" not in said.out + said.err and "\x1b" not in said.out + said.err
