"""Error types shared by every layer.

``UserInputError`` marks mistakes in what a user gave (a URDF, a scene, command-line
arguments, a message): the command line prints it on one line and exits with status 2, and
a node reports it without crashing. Its message says what was wrong and where.
"""


class UserInputError(ValueError):
    """Bad input from a user: the message names what was wrong and where."""
