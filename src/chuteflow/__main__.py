"""``python -m chuteflow``: same as the ``chuteflow`` command."""

from chuteflow.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
