"""Error types shared by every layer.

``UserInputError`` marks mistakes in what a user gave (a URDF, a scene, command-line
arguments, a message): the command line prints it on one line and exits with status 2, and
a node reports it without crashing. Its message says what was wrong and where.
"""


class UserInputError(ValueError):
    """Bad input from a user: the message names what was wrong and where."""


class URDFError(UserInputError):
    """A URDF that cannot be loaded: the message names the file, the line, the element and
    the reason."""


class SingularMassMatrixError(URDFError):
    """Forward dynamics asked of a robot whose joint-space mass matrix is singular (a moving
    joint whose subtree carries no mass): the message names those joints."""
