"""Markdown read into the document model: what each construct becomes, checked on both
renderings (the HTML must show no Markdown syntax)."""

import re

from orchestrator.report.document import (Bullets, Code, Document, Paragraph, Preformatted,
                                          Strong, Table)
from orchestrator.report.html import render_html
from orchestrator.report.markdown_text import add_markdown

NOTES = """Intro line one
and two, see [errata](errata.md).

# Motor

| `param` | value | norm |
|---|---:|---|
| `R` | 1.2 Ohm | `|v| <= 1` |

- first item
  continued
- second with **bold**

```
code | kept `as is`
```

## Deeper
Text after a heading.
"""


def test_each_construct_becomes_its_block():
    document = Document("Plant")
    add_markdown(document, NOTES, level=2)
    (intro, motor, deeper) = document.sections
    assert (intro.heading, intro.level) == ("Plant", 3)       # text before the first heading
    assert intro.blocks[0].content == ("Intro line one and two, see errata.",)
    assert (motor.heading, motor.level, deeper.level) == ("Motor", 3, 4)
    table, bullets, code = motor.blocks
    assert isinstance(table, Table) and [c.name for c in table.columns] == ["param", "value",
                                                                            "norm"]
    assert table.rows == [["`R`", "1.2 Ohm", "`|v| <= 1`"]]   # a pipe inside code stays
    assert isinstance(bullets, Bullets) and bullets.items == [
        ("first item continued",), ("second with ", Strong("bold"))]
    assert isinstance(code, Preformatted) and code.text == "code | kept `as is`"
    assert isinstance(deeper.blocks[0], Paragraph)


def test_the_html_shows_no_markdown_syntax():
    document = Document("Plant")
    add_markdown(document, NOTES, level=2)
    page = render_html(document)
    prose = re.sub(r"<code>.*?</code>|<pre>.*?</pre>", "", page, flags=re.S)
    for syntax in ("`", "**", "](", "\n#", "|---"):
        assert syntax not in prose, syntax
    assert "<code>|v| &lt;= 1</code>" in page and "<strong>bold</strong>" in page


def test_a_line_that_looks_like_a_table_but_is_not_is_text():
    document = Document("x")
    add_markdown(document, "| not a table\nnext line")
    assert document.sections[0].blocks[0].content == ("| not a table next line",)
    assert Code("R") in Document("y").section("s").paragraph("`R`").blocks[0].content
