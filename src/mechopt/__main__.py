"""`python -m mechopt` is the `mechopt` command, and `main` its entry point (pyproject.toml): it
answers `mechopt --version` before the command's modules (the registry, numpy, the solvers) load."""
import sys


def main(argv=None) -> int:
    if (sys.argv[1:] if argv is None else list(argv)) == ["--version"]:
        from mechopt import __version__
        print(f"mechopt {__version__}")
        return 0
    try:
        from mechopt.cli import main as command
    except KeyboardInterrupt:       # Ctrl-C while the command was still loading: nothing was done
        return 130
    return command(argv)


if __name__ == "__main__":
    sys.exit(main())
