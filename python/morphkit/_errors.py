"""The exceptions morphkit raises. Every one derives from :class:`MorphkitError`, itself a
:class:`ValueError`; errors about files also derive from :class:`OSError`."""


class MorphkitError(ValueError):
    """Base class of every error morphkit raises; the message is the library's."""


class MeshError(MorphkitError):
    """An array or mesh is malformed: wrong shape or dtype, NaN, out-of-range index."""


class FileError(MorphkitError, OSError):
    """A file could not be read, parsed or written; the message names the file."""


class BlendError(MorphkitError):
    """A physical blend could not be set up or solved."""


class TransferError(MorphkitError):
    """A correspondence or a deformation transfer failed."""
