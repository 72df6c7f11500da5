"""Contact models. Each returns a force and its stiffness so both integrators can use it."""
