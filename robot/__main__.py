"""``python -m robot``: regenerate ``robot/assets/superlimb.{urdf,xml}`` from the default
:class:`robot.superlimb.params.SuperLimbParams` (a test checks that the files are up to date)."""

from .superlimb.model_files import write_assets

for written in write_assets():
    print(written)
