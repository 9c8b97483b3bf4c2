"""`python -m transfertwin`."""

from transfertwin.cli import main

raise SystemExit(main())
