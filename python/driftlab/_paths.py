"""Where the driftlab program is, for the jobs of a sweep."""

import os
import shutil

_HERE = os.path.dirname(os.path.abspath(__file__))
# The build tree's BUILD/bin (this package in BUILD/python/driftlab), then the installation's
# PREFIX/bin (this package in PREFIX/lib/python3.X/dist-packages/driftlab).
_CANDIDATES = [os.path.join(_HERE, "..", "..", "bin", "driftlab"),
               os.path.join(_HERE, "..", "..", "..", "..", "bin", "driftlab")]


def use_installed_assets():
    """An installed package reads driftlab's assets from PREFIX/share/driftlab/assets, as the
    installed program does (scenes/assets.hpp), unless DRIFTLAB_ASSET_DIR says otherwise."""
    assets = os.path.join(_HERE, "..", "..", "..", "..", "share", "driftlab", "assets")
    if not os.environ.get("DRIFTLAB_ASSET_DIR") and os.path.isdir(assets):
        os.environ["DRIFTLAB_ASSET_DIR"] = os.path.normpath(assets)


def cli():
    """$DRIFTLAB, else the build's driftlab, else the installation's, else the one on PATH."""
    if os.environ.get("DRIFTLAB"):
        return os.environ["DRIFTLAB"]
    for path in _CANDIDATES:
        if os.access(path, os.X_OK):
            return os.path.normpath(path)
    found = shutil.which("driftlab")
    if not found:
        raise FileNotFoundError("the driftlab program: not built here, not installed and not on "
                                "PATH; set DRIFTLAB to its path")
    return found
