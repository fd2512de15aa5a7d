import pathlib
import sys

# `import core` with the repository root on sys.path, exactly as tools outside the project do it.
ROOT = pathlib.Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))
