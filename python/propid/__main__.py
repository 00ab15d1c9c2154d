"""``python -m propid …`` runs the ``propid`` command."""

from ._cli import main

main()
