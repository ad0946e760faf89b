"""Every bad input of ``bad_inputs.py``: our exception naming the field (API); exit 2 and one line on stderr that
names it, brackets intact, no traceback (CLI). A case that ends in any other exception fails here."""

from __future__ import annotations

import pytest

from framework.cli import EXIT_INPUT, main
from framework.errors import MetaikError
from tests.conftest import without_compile_notices
from tests.fuzz.bad_inputs import API_CASES, CLI_CASES


@pytest.mark.parametrize("case", CLI_CASES, ids=[f"{c.category}: {c.id}" for c in CLI_CASES])
def test_cli_bad_input_is_one_line_exit_2(case, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    argv = list(case.argv)
    if case.file_text is not None:
        (tmp_path / "t.toml").write_text(case.file_text)
        argv = [a.replace("{file}", "t.toml") for a in argv]
    code = main(argv)
    out, err = capsys.readouterr()
    err = without_compile_notices(err)
    assert code == EXIT_INPUT, (code, out[-2000:], err)
    assert err.count("\n") == 1 and err.startswith("error: "), err
    for name in case.names:
        assert name in err, (name, err)


def test_cli_messages_keep_their_brackets(tmp_path, monkeypatch, capsys):
    """Messages are printed as text, not console markup: ``[task]`` and ``[nan, ...]`` survive."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.toml").write_text("[solver]\nname = 'de'\n")
    assert main(["run", "t.toml"]) == EXIT_INPUT
    assert "missing [task] table" in capsys.readouterr().err


@pytest.mark.parametrize("case", API_CASES, ids=[c.id for c in API_CASES])
def test_api_bad_input_raises_our_error_naming_the_field(case):
    with pytest.raises(MetaikError) as caught:
        case.call()
    for name in case.names:
        assert name in str(caught.value), (name, str(caught.value))
