"""The `ur_sim` node (placeholder until the simulator lands)."""
import sys


def main(argv: list[str] | None = None) -> int:
    """Entry point of `ur_sim`."""
    print('ur_sim: not implemented yet (see the ur_sim issue); exiting.', file=sys.stderr)
    return 0


if __name__ == '__main__':
    sys.exit(main())
