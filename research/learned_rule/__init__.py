"""A rule learned from the switch-priced oracle (research, not installed; the product never imports it).

:mod:`.features`: causal features computed online from what the arbiter is given each step;
:mod:`.policy`: the learned rule (a multinomial logistic model over authority levels, with hysteresis) and
the controller factories that run it or log its features under another policy; :mod:`.fit`: the fit on
teacher labels; :mod:`.teacher`: the priced oracle's schedules searched and replayed in the closed loop.
"""
