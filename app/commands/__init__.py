"""Subcommands of the ``credal-fusion`` CLI beyond ``serve``."""
