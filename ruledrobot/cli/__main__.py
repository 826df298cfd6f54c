"""``python -m ruledrobot.cli``: the command line."""

from . import main

main()
