"""`python -m mechopt` is the `mechopt` command."""
import sys

try:
    from mechopt.cli import main
except KeyboardInterrupt:       # Ctrl-C while the command was still loading: nothing was done
    sys.exit(130)

sys.exit(main())
