"""``mpcshare run``: the shared controller on a real arm over ROS 2 topics (DDS, no ROS install needed).

- :mod:`mpcshare.runtime.messages` — ROS 2 messages as Cyclone DDS types with ROS 2's DDS names;
- :mod:`mpcshare.runtime.transport` — the participant (loopback by default), readers, writers;
- :mod:`mpcshare.runtime.config` — the arm's TOML configuration, checked;
- :mod:`mpcshare.runtime.config_reader` — typed TOML reads with one-line errors, field paths checked;
- :mod:`mpcshare.runtime.setup` — the arm and the controller from it;
- :mod:`mpcshare.runtime.watchdog` — per-input deadlines and the protective stop;
- :mod:`mpcshare.runtime.convert` — messages ↔ the controller's arrays;
- :mod:`mpcshare.runtime.loop` — the loop at the control rate;
- :mod:`mpcshare.runtime.tick_profile` — where the ticks' time goes, and why a long period was long;
- :mod:`mpcshare.runtime.gc_policy` — the garbage collector while the loop ticks;
- :mod:`mpcshare.runtime.remote` — the robot stand-in's side (``mpcshare sim --serve``);
- :mod:`mpcshare.runtime.stand_in_command` — each command form as the stand-in follows it;
- :mod:`mpcshare.runtime.live` — the Foxglove live view.

Needs the ``cyclonedds`` package (``pip install mpcshare[ros]``); importing this package alone does not.
"""
