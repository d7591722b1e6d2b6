#!/usr/bin/env python3
"""check-config-docs.py — every key a config parser accepts is named on its documentation page.

Usage: scripts/check-config-docs.py [REPO_ROOT]

The parsers refuse unknown keys with `rejectUnknownKeys({"a", "b", ...})`; those lists are the
truth of what a file may hold. For each parser source below, every key of its lists must appear
inside a backtick span of its page (as `key`, or as the last part of a dotted path such as
`filter.motion.key`), so a key added to a parser without a line in the docs fails the test suite.
Written as `min/max_x`, only `max_x` counts: name both keys. Ranges and defaults are not checked
(an audit on 2026-11-24 found and fixed those by hand). Standard library only; exit 1 with one
line per undocumented key, 0 when all are named.
"""
import os
import re
import sys

# Parser source -> the page that documents its keys.
PAGES = {
    "common/config/src/slam_config.cpp": "docs/slam-process.md",
    "procs/slam/map_file.cpp": "docs/slam-process.md",
    "procs/features/detectors.cpp": "docs/detectors.md",
    "procs/launch/launcher.cpp": "docs/launch-file.md",
    "common/config/src/world_config.cpp": "docs/world-file.md",
}


def parser_keys(source_text):
    """The keys of every rejectUnknownKeys({...}) call, and the number of calls not read."""
    keys = set()
    calls = re.findall(r"rejectUnknownKeys\(\s*\{(.*?)\}\s*\)", source_text, re.S)
    for call in calls:
        keys.update(re.findall(r'"([A-Za-z0-9_]+)"', call))
    # A call the pattern cannot read (a list built elsewhere, a new layout) would go unchecked.
    unread = source_text.count("rejectUnknownKeys(") - len(calls)
    return keys, unread


def documented_words(page_text):
    words = set()
    for span in re.findall(r"`([^`]*)`", page_text):  # inline code may wrap a line
        words.update(re.findall(r"[A-Za-z0-9_]+", span))
    return words


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    missing = 0
    for source, page in PAGES.items():
        try:
            with open(os.path.join(root, source), encoding="utf-8") as f:
                keys, unread = parser_keys(f.read())
            with open(os.path.join(root, page), encoding="utf-8") as f:
                words = documented_words(f.read())
        except OSError as e:
            print(f"check-config-docs: cannot read {e.filename}: {e.strerror}")
            return 1
        if unread:
            print(f"check-config-docs: {source}: {unread} rejectUnknownKeys call(s) not of the form "
                  "rejectUnknownKeys({\"key\", ...}): their keys cannot be checked")
            return 1
        if not keys:
            print(f"check-config-docs: {source}: no rejectUnknownKeys list found (moved? update PAGES)")
            return 1
        undocumented = sorted(keys - words)
        for key in undocumented:
            print(f"check-config-docs: key '{key}' accepted by {source} is not named in {page}")
        if not undocumented:
            print(f"check-config-docs: {source}: {len(keys)} keys, all named in {page}")
        missing += len(undocumented)
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
