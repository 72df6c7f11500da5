"""``python -m deformx``: the same as the ``deformx`` command."""

from deformx.cli import app

if __name__ == "__main__":
    app(prog_name="deformx")
