"""``python -m swarm_ik.cli …``: the same as the ``swarm-ik`` console script."""

from swarm_ik.cli import main

raise SystemExit(main())
