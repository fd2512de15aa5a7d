"""The README's map of the repository and its make targets match the repository."""

import re

from bpy_route import ROOT

README = (ROOT / "README.md").read_text()
# Caches of tools, never committed and never meant for a reader.
TOOL_CACHES = {".git", ".hypothesis", ".benchmarks", ".pytest_cache", ".ruff_cache", "__pycache__"}


def test_what_is_in_here_lists_every_top_level_folder():
    table = README.split("## What is in here", 1)[1].split("\n## ", 1)[0]
    listed = set(re.findall(r"`([^`/]+)/`", table))
    folders = {path.name for path in ROOT.iterdir() if path.is_dir() and path.name not in TOOL_CACHES}
    assert folders <= listed, folders - listed


def test_every_make_target_a_reader_runs_is_in_the_readme():
    makefile = (ROOT / "Makefile").read_text()
    for target in (
        "demo",
        "test",
        "test-core",
        "test-quick",
        "lint",
        "format",
        "build",
        "dist",
        "envs",
        "env-bpy45",
        "env-bpy52",
        "clean",
    ):
        # A rule line names the target among those before its colon (``env-bpy45 env-bpy52 env-lint:``).
        assert re.search(rf"^([\w-]+ )*{re.escape(target)}( [\w-]+)*:", makefile, re.M), target
        assert f"make {target}" in README, target
