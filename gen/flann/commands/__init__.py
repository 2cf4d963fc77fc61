"""One module per ``flann`` subcommand: ``HELP``, ``add_arguments(parser)``, ``run(args)``."""
