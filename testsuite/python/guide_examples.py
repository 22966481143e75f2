"""The code examples of the user guide (doc/*.md) as scripts.

All ```python blocks of one page, in order, make one script, together with
the page's hidden setups, if any, where they stand: HTML comments that start
with ``<!-- guide-setup`` (setup a reader need not see, e.g. a file to read).
Used by test_user_guide.py; ``python3 guide_examples.py PAGE.md`` prints a
page's script.
"""
import re
import sys

_PIECE = re.compile(r"^```python[^\n]*\n(?P<block>.*?)^```[ \t]*$"
                    r"|^<!-- guide-setup[ \t]*\n(?P<setup>.*?)^-->[ \t]*$", re.S | re.M)


def page_script(text):
    """(script, number of python blocks) of one page's Markdown text: its
    python blocks and hidden setups in the order they appear."""
    parts, n_blocks = [], 0
    for m in _PIECE.finditer(text):
        if m.group("block") is not None:
            n_blocks += 1
            parts.append(f"# --- example {n_blocks}\n{m.group('block')}")
        else:
            parts.append(f"# --- hidden setup\n{m.group('setup')}")
    return "\n".join(parts), n_blocks


if __name__ == "__main__":
    with open(sys.argv[1], encoding="utf-8") as f:
        print(page_script(f.read())[0])
