"""A result shows in a notebook as a small HTML table (``_repr_html_``): its rows say what the
result's own fields say, and every text in it is escaped."""

from __future__ import annotations

import dataclasses
from html.parser import HTMLParser

import pytest

from contactqp.core.status import status_counts
from test_result import KINDS


class TableReader(HTMLParser):
    """``{header: cell}`` of a table of ``<tr><th>header</th><td>cell</td></tr>`` rows, its
    caption, and every tag met (so that an unescaped tag shows up)."""

    def __init__(self):
        super().__init__()
        self.rows: dict[str, str] = {}
        self.caption = ""
        self.tags: list[str] = []
        self._cell: str | None = None
        self._texts = {"th": "", "td": "", "caption": ""}

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        if tag in self._texts:
            self._cell = tag
            self._texts[tag] = ""

    def handle_endtag(self, tag):
        self._cell = None
        if tag == "tr":
            self.rows[self._texts["th"]] = self._texts["td"]
        if tag == "caption":
            self.caption = self._texts["caption"]

    def handle_data(self, data):
        if self._cell is not None:
            self._texts[self._cell] += data


def read(markup: str) -> TableReader:
    reader = TableReader()
    reader.feed(markup)
    reader.close()
    return reader


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_the_table_says_what_the_result_says(kind):
    result = KINDS[kind]()
    table = read(result._repr_html_())
    assert table.caption == type(result).__name__
    assert set(table.tags) <= {"table", "caption", "tr", "th", "td"}
    assert table.rows["method"] == result.method
    assert table.rows["success"] == f"{result.success} (status {result.status})"
    assert table.rows["message"] == result.message
    assert table.rows["iterations"] == str(result.iterations)
    assert float(table.rows["seconds"]) == pytest.approx(result.seconds, rel=1e-2, abs=1e-12)
    counts = status_counts(result.contact_status)
    shown = table.rows["contacts"]
    assert shown.startswith(f"{result.n_contacts}: ")
    for status in type(result).STATUSES:
        assert f"{counts[status.label]} {status.label}" in shown
    certificate = result.certificate
    assert table.rows["certificate"].startswith("passed: worst residual")
    assert float(table.rows["certificate"].split()[3]) == pytest.approx(
        certificate.worst, rel=1e-2, abs=1e-300
    )
    for name in certificate.as_dict():
        assert (name in table.rows["residuals"]) == (name not in ("tol", "passed"))


def test_text_is_escaped_and_a_failed_certificate_says_so():
    result = KINDS["frictionless"]()
    message = "<script>alert('x')</script> & \"more\""
    failing = dataclasses.replace(result.certificate, penetration=1.0)
    shown = dataclasses.replace(result, message=message, certificate=failing, success=False)
    markup = shown._repr_html_()
    assert "<script>" not in markup and "&lt;script&gt;" in markup and "&amp;" in markup
    table = read(markup)
    assert table.rows["message"] == message  # the parser unescapes: the text is intact
    assert table.rows["success"] == f"False (status {result.status})"
    assert table.rows["certificate"].startswith("failed: worst residual 1.00e+00")
