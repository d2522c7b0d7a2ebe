"""The equations atlas maps: each a :class:`~atlas.models.base.Model` (its description) and
a planner module, found by name in :mod:`atlas.models.registry`. The damped pendulum with
constant torque (:mod:`atlas.models.pendulum`) is the first, and the default."""
