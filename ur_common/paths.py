"""Where the package's data lives: the source tree when run from it, else the installed share directory."""
from __future__ import annotations

from pathlib import Path

_SOURCE_ROOT = Path(__file__).resolve().parents[1]


def package_dir() -> Path:
    """The directory holding config/ and meshes/ (the repository root, or share/ur_sim_driver when installed)."""
    if (_SOURCE_ROOT / 'config').is_dir():
        return _SOURCE_ROOT
    try:
        from ament_index_python.packages import get_package_share_directory
        return Path(get_package_share_directory('ur_sim_driver'))
    except Exception:  # not installed, or no ament index: report the source path in any error that follows
        return _SOURCE_ROOT


def config_dir() -> Path:
    """The package's config/ directory."""
    return package_dir() / 'config'
