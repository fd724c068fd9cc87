"""python -m kestrel COMMAND: the same as the `kestrel` console command (kestrel.cli)."""
from .cli import main

raise SystemExit(main())
