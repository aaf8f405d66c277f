"""The command line's subcommands, one module per area (``training``, ``server``, ``league``, ``web``).

This package sits above every other: it may import any of them (lazily, inside the ``_run_*`` functions, so
``--help`` stays fast), and nothing imports it but ``rocketdrl_ma.cli``.
"""
