"""Numbers typed or read are plain ASCII, as pandas reads them.

Python's ``float`` (and numpy's, which calls it) takes ``"1_0"`` as 10 and the
digits of other scripts; ``pandas.read_csv`` and ``numpy.loadtxt`` of a file the
workbench writes would not, so neither does the workbench.
"""

from __future__ import annotations

import pytest

from tests.conftest import run_cli
from workbench.cli import EXIT_BAD_INPUT
from workbench.validation import parse_float, parse_int

#: Underscores, Arabic-Indic digits, full-width digits.
NOT_PLAIN = ["1_0", "\u0661\u0660", "\uff11\uff10", "1_000.5", "\u0663.\u0665"]


@pytest.mark.parametrize("text", NOT_PLAIN)
def test_underscores_and_other_digits_are_refused(text: str) -> None:
    assert float(text) > 0  # Python's float takes them
    with pytest.raises(ValueError, match="plain ASCII"):
        parse_float(text)
    if "." not in text:
        with pytest.raises(ValueError, match="plain ASCII"):
            parse_int(text)


def test_plain_numbers_read_as_float_does() -> None:
    for text in ("10", "-1.5e-3", " 2.5 ", "inf", "nan", "0"):
        assert str(parse_float(text)) == str(float(text))
    assert parse_int("42") == 42


@pytest.mark.parametrize("text", NOT_PLAIN[:3])
def test_the_command_line_refuses_them(capsys, text: str) -> None:
    code, out, err = run_cli(capsys, "fk", "--robot", "puma560", "--deg", text,
                             *["0"] * 5)  # fmt: skip
    assert code == EXIT_BAD_INPUT and out == "" and err.count("\n") == 1
    assert "not a number" in err
