import sys

try:
    from .cli import main
except KeyboardInterrupt:  # Ctrl-C while the package is still being imported
    print("pointscale: interrupted", file=sys.stderr)
    sys.exit(130)

sys.exit(main())
