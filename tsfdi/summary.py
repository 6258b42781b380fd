"""The :class:`Summary` returned by every ``summary()`` of tsfdi (models, order selection, decisions).

A summary is data, not a string: a title, header rows ``(key, value)``, titled tables (pandas DataFrames of
numbers, which stay available as ``summary.tables``) and notes. It prints as plain text (``str(summary)``,
:meth:`Summary.as_text`) and renders as HTML tables in a notebook (``_repr_html_``, :meth:`Summary.as_html`),
as statsmodels' ``Summary`` does.
"""

from __future__ import annotations

import html
import textwrap
from dataclasses import dataclass, field
from numbers import Integral, Real

import numpy as np
import pandas as pd

__all__ = ["Summary"]

#: significant digits of the numbers in a summary
DIGITS = 6


def _cell(value: object) -> str:
    """One table cell or header value as text: floats to :data:`DIGITS` significant digits."""
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    if isinstance(value, Integral):
        return str(int(value))
    if isinstance(value, Real):
        return f"{float(value):.{DIGITS}g}"
    return str(value)


def _cells(table: pd.DataFrame) -> pd.DataFrame:
    """The table with every cell formatted by :func:`_cell` (index and column labels kept)."""
    return pd.DataFrame([[_cell(v) for v in row] for row in table.itertuples(index=False, name=None)],
                        index=table.index, columns=table.columns)


def _html_table(cells: pd.DataFrame) -> str:
    """An HTML table of formatted cells: a header row, then one row per index entry (its label as ``<th>``)."""
    esc = html.escape
    head = "".join(f"<th>{esc(str(c))}</th>" for c in cells.columns)
    body = "".join(f"<tr><th>{esc(str(i))}</th>" + "".join(f"<td>{esc(v)}</td>" for v in row) + "</tr>"
                   for i, row in zip(cells.index, cells.itertuples(index=False, name=None)))
    corner = esc("" if cells.index.name is None else str(cells.index.name))
    return f"<table><thead><tr><th>{corner}</th>{head}</tr></thead><tbody>{body}</tbody></table>"


@dataclass(frozen=True, eq=False)
class Summary:
    """A summary of a result: header rows and titled tables, as text or HTML.

    Attributes
    ----------
    title : str
        What is summarised (e.g. ``"VAR results"``).
    header : list of (str, object)
        Key / value rows (model, order, number of observations, criteria, ...).
    tables : list of (str, pandas.DataFrame)
        Titled tables of numbers (e.g. one coefficient table per equation). The frames hold the values
        themselves; only the rendering rounds them (to :data:`DIGITS` significant digits).
    notes : list of str
        Lines printed after the tables.

    Examples
    --------
    >>> s = tsfdi.AR(y, 2).fit().summary()      # doctest: +SKIP
    >>> print(s)                                # doctest: +SKIP
    >>> s.tables[0][1]["std err"]               # doctest: +SKIP
    """

    title: str
    header: list = field(default_factory=list)
    tables: list = field(default_factory=list)
    notes: list = field(default_factory=list)

    def as_text(self) -> str:
        """Plain text: the title, the header rows, each table under its title, the notes."""
        parts = []
        if self.header:
            width = max(len(str(k)) for k, _ in self.header)
            parts.append("\n".join(f"{str(k):<{width}}  {_cell(v)}" for k, v in self.header))
        for title, table in self.tables:
            text = _cells(table).to_string()
            parts.append(f"{title}\n{'-' * max(len(title), max(map(len, text.splitlines())))}\n{text}")
        if self.notes:
            parts.append("\n".join(textwrap.fill(n, 100, subsequent_indent="  ") for n in self.notes))
        body = "\n\n".join(parts)
        rule = "=" * max([len(self.title)] + [len(line) for line in body.splitlines()])
        return f"{self.title.center(len(rule)).rstrip()}\n{rule}\n{body}\n{rule}"

    def as_html(self) -> str:
        """HTML: the title, the header rows as a two-column table, each table under its title, the notes."""
        esc = html.escape
        parts = [f"<div class=\"tsfdi-summary\"><h4>{esc(self.title)}</h4>"]
        if self.header:
            rows = "".join(f"<tr><th>{esc(str(k))}</th><td>{esc(_cell(v))}</td></tr>" for k, v in self.header)
            parts.append(f"<table><tbody>{rows}</tbody></table>")
        for title, table in self.tables:
            parts.append(f"<p><b>{esc(title)}</b></p>{_html_table(_cells(table))}")
        if self.notes:
            parts.append("<p>" + "<br>".join(esc(n) for n in self.notes) + "</p>")
        return "".join(parts) + "</div>"

    def __str__(self) -> str:
        return self.as_text()

    def __repr__(self) -> str:
        return self.as_text()

    def _repr_html_(self) -> str:
        return self.as_html()
