"""Write a benchmark's section into a markdown file, keeping the rest of the file."""

from __future__ import annotations

import os


def replace_section(path: str, section: str) -> None:
    """Replace the ``## ...`` section whose heading is ``section``'s first line (up to the next
    ``## `` heading), or append it if the file has none; creates the file if missing."""
    heading = section.split("\n", 1)[0] + "\n"
    text = open(path).read() if os.path.exists(path) else "# Benchmarks\n\n"
    start = text.find(heading)
    if start >= 0:
        end = text.find("\n## ", start + len(heading))
        text = text[:start] + section + ("\n" + text[end + 1:] if end >= 0 else "")
    else:
        text = text.rstrip() + "\n\n" + section
    with open(path, "w") as fh:
        fh.write(text)


def publish(section: str, path: str | None) -> None:
    """Print a benchmark's section, and write it into markdown file ``path`` if given
    (:func:`replace_section`): what each script's ``--write`` does."""
    print(section)
    if path:
        replace_section(path, section)
