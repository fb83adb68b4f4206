"""``python -m simlunar.cli``: the ``simlunar`` command."""

from simlunar.cli import main

main()
