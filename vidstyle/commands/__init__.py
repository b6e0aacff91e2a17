"""CLI command modules; each exposes ``register(app)`` (discovered by ``vidstyle.cli``)."""
