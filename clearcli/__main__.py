"""``python -m clearcli``: the same program as the ``clear`` script (for a venv whose
scripts folder is not on PATH, or a notebook's ``!python -m clearcli plan ...``)."""

from clearcli.cli import main

if __name__ == "__main__":
    main()
