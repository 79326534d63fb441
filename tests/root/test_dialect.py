"""The root's table-dialect sniffer (``jointwear.dialect``), which the metrology readers and the
own-data importers share: each decision against tables whose dialect is known by construction."""

from __future__ import annotations

import subprocess
import sys

import pytest

from jointwear import dialect
from jointwear.errors import BadInputError


@pytest.mark.parametrize(
    ("lines", "expected"),
    [
        (["0,25;1,5", "1,0;2,25", "2,5;-3,75"], (";", ",")),  # semicolon, decimal comma
        (["0.25\t1.5", "1.0\t2.25", "2.5\t-3.75"], ("\t", ".")),
        (["0.25, 1.5, 3", "1.0, 2.25, 4", "2.5, 3.75, 5"], (",", ".")),
        (["0.25  1.5", "1.0   2.25", "2.5 3.75"], (" ", ".")),  # whitespace runs
    ],
)
def test_delimiter_and_decimal_of_known_tables(lines, expected):
    assert dialect.sniff_separators(lines) == expected


def test_integers_split_by_a_comma_with_leading_zeros_are_decimal_commas():
    # "1,012" read as two integer columns would give 12 instead of 1.012
    found = dialect.sniff_separators(["1,012", "2,034", "3,056"])
    assert found is not None and found[1] == ","


def test_a_given_delimiter_is_kept_and_text_is_no_reading():
    assert dialect.sniff_separators(["1,5;2", "3;4,25"], delimiter=";") == (";", ",")
    assert dialect.sniff_separators(["abc;def", "ghi;jkl"]) is None


def test_thousands_mark_only_when_unambiguous():
    assert dialect.sniff_thousands(["8,001.234;1.5", "999.5;2.0"], ";") == ","
    # 0.458 could be 458 grouped by a point: no mark is decided
    assert dialect.sniff_thousands(["0.458;1.5", "1.5;2.0"], ";") is None


def test_delimiter_names_and_refusal():
    assert [dialect.delimiter_char(n) for n in ("tab", "space", ";", None)] == [
        "\t",
        " ",
        ";",
        None,
    ]
    with pytest.raises(BadInputError, match="'pipe' is not supported"):
        dialect.delimiter_char("pipe")


def test_the_sniffer_is_light():
    code = "import sys, jointwear.dialect; print('numpy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
