"""The subcommands of the ``mpcshare`` command line, one module per purpose.

- :mod:`mpcshare.commands.base` — :class:`Command`, :class:`CommandError`, argument
  types, output-folder and data-loading helpers shared by every subcommand;
- :mod:`mpcshare.commands.data` — ``inspect`` and ``generate``;
- :mod:`mpcshare.commands.ros_import` — ``import`` (ROS bags into a data set);
- :mod:`mpcshare.commands.analysis` — ``analyze`` (and the analysis options ``demo`` shares);
- :mod:`mpcshare.commands.train` — ``train`` (a model bundle, or the K sweep);
- :mod:`mpcshare.commands.sim` — ``sim`` (closed-loop comparison of strategies);
- :mod:`mpcshare.commands.demo` — ``demo``, the main job on the default data.

The registry of subcommands is :data:`mpcshare.cli.COMMANDS`.
"""
