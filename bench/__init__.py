"""The benchmark suite of HC Smooth: `python bench/run.py NAME` (bench/README.md)."""
