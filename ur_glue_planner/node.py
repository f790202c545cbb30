"""The `ur_glue_planner` node (placeholder until the planner lands)."""
import sys


def main(argv: list[str] | None = None) -> int:
    """Entry point of `ur_glue_planner`."""
    print('ur_glue_planner: not implemented yet (see the planner issue); exiting.', file=sys.stderr)
    return 0


if __name__ == '__main__':
    sys.exit(main())
