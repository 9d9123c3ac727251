"""Fanuc's abbreviated macro words: the first two letters of a custom macro word stand for it (``WH[…]DO1``
is ``WHILE[…]DO1``, ``GO10`` is ``GOTO10``, ``SQ[#1]`` is ``SQRT[#1]``), as a Fanuc control reads them.

:func:`expand` writes a block's abbreviations out before the scanner reads it. An abbreviation is only
recognised where no address could stand, so no block that is valid without it changes meaning:

* in an expression — inside brackets, or after an assignment's ``=`` (where there are no addresses): a
  function's two letters followed by ``[`` (``SI[``, ``AT[``), an operator's followed by something that
  is not a letter (``#1AN#2``, ``[#3]MO2``);
* outside brackets, at the head of a statement (the block's start, after its N or O word or its ``/``
  skip mark, or right after ``IF[…]``): ``WH[``, ``GO`` before a number, ``#`` or ``[``, ``EN`` before a
  number, ``TH`` before ``#``. (An address letter needs a number after it: ``W`` cannot take ``H``, ``G``
  cannot take ``O``.)

A full word is never touched (``AND``: ``AN`` is followed by a letter).
"""

from __future__ import annotations

from collections.abc import Mapping

#: Abbreviation → word (Fanuc Series 0i custom macro words; the two-letter words IF, DO, OR, LN, EQ, NE, GT,
#: GE, LT, LE are their own abbreviations).
FANUC_ABBREVIATIONS: Mapping[str, str] = {
    # statements
    "WH": "WHILE", "GO": "GOTO", "EN": "END", "TH": "THEN",
    # functions
    "SI": "SIN", "CO": "COS", "TA": "TAN", "AS": "ASIN", "AC": "ACOS", "AT": "ATAN", "SQ": "SQRT",
    "AB": "ABS", "BI": "BIN", "BC": "BCD", "RO": "ROUND", "FI": "FIX", "FU": "FUP", "EX": "EXP",
    # operators
    "AN": "AND", "XO": "XOR", "MO": "MOD",
}  # fmt: skip
_STATEMENTS = {"WH": "[", "GO": "0123456789#[", "EN": "0123456789", "TH": "#"}
_OPERATORS = frozenset({"AN", "XO", "MO"})


def expand(text: str, words: Mapping[str, str]) -> str:
    """``text`` (one block, upper case, no blanks or comments) with its abbreviations written out (module
    docstring); ``words`` is the dialect's table (abbreviation → word)."""
    if not words or not any(a in text for a in words):
        return text
    out: list[str] = []
    depth = 0
    assigned = False  # after the '=' of an assignment: the rest of the block is an expression
    i, n = 0, len(text)
    head = _statement_start(text)
    while i < n:
        c = text[i]
        if c == "[":
            depth += 1
        elif c == "]":
            depth -= 1
            if depth == 0 and text.startswith("IF", head) and head < i:
                head = i + 1  # after IF[…]: GOTO or THEN
        elif c == "=" and depth == 0:
            assigned = True
        pair = text[i : i + 2]
        after = text[i + 2 : i + 3]
        previous = text[i - 1] if i else ""
        word = words.get(pair)
        if word is not None and not ("A" <= previous <= "Z") and not ("A" <= after <= "Z"):
            if depth > 0 or assigned:
                if (pair in _OPERATORS and after) or (pair not in _OPERATORS and pair not in _STATEMENTS
                                                      and after == "["):  # fmt: skip
                    out.append(word)
                    i += 2
                    continue
            elif i == head and pair in _STATEMENTS and after and after in _STATEMENTS[pair]:
                out.append(word)
                i += 2
                continue
        out.append(c)
        i += 1
    return "".join(out)


def _statement_start(text: str) -> int:
    """Where a block's statement starts: after its skip marks (``/``, ``/3``) and its O and N words."""
    i, n = 0, len(text)
    while i < n and text[i] == "/":
        i += 1
        while i < n and text[i].isdigit():
            i += 1
    for letter in "ON":
        if i < n and text[i] == letter:
            i += 1
            while i < n and (text[i].isdigit() or text[i] == "."):
                i += 1
    return i
