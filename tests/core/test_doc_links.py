"""Every relative link of the Markdown files (README, docs/, bench/) points to a file that exists."""

import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[2]
SKIP = {".git", ".envs", "build", "dist", "demo_output", ".pytest_cache", ".ruff_cache"}
LINK = re.compile(r"\]\(([^)\s]+)\)")


def markdown_files():
    return [p for p in ROOT.rglob("*.md") if not SKIP & set(p.relative_to(ROOT).parts)]


def broken_links(path):
    broken = []
    for target in LINK.findall(path.read_text()):
        if re.match(r"[a-z]+:", target) or target.startswith("#"):
            continue
        if not (path.parent / target.split("#", 1)[0]).exists():
            broken.append(target)
    return broken


def test_every_relative_link_resolves():
    broken = {str(p.relative_to(ROOT)): links for p in markdown_files() if (links := broken_links(p))}
    assert not broken, broken
