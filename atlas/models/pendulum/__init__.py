"""The damped pendulum with constant torque, θ̈ + 2αθ̇ + ω0² sin θ = τ: atlas's first model.
Its description (:mod:`~atlas.models.pendulum.description`) is data every layer reads; its
planner (:mod:`~atlas.models.pendulum.plan`) prepares each parameter point from the physics,
kernels and exact boundaries."""
