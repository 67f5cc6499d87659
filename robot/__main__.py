"""``python -m robot``: regenerate ``robot/assets/superlimb.{urdf,xml}`` from the default
:class:`robot.superlimb.SuperLimbParams` (a test checks that the files are up to date)."""

from .model_files import write_assets

for written in write_assets():
    print(written)
