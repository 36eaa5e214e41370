"""Outputs kept or discarded as a whole: every file is written under a temporary name beside its target and
renamed on a clean close, so a failed job leaves no partial output."""


class Output:
    """An output written to a temporary file: a context manager that closes it (renaming it into place) when the
    block succeeds and aborts it (discarding it) when the block raises. Subclasses define ``close`` and ``abort``."""

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            self.close()
        else:
            self.abort()


class Recording(Output):
    """An MCAP file (``self._mcap``) and an optional rerun recording (``self._rerun``), kept or discarded
    together."""

    def close(self):
        """Finish both files and rename them into place."""
        self._mcap.close()
        if self._rerun is not None:
            self._rerun.close()

    def abort(self):
        """Discard both files (either may not have been opened yet)."""
        if self._mcap is not None:
            self._mcap.abort()
        if self._rerun is not None:
            self._rerun.abort()
