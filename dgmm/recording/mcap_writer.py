"""An MCAP file of Foxglove protobuf messages and dgmm's JSON messages, with deterministic log times, written
atomically."""
import json
import os
from pathlib import Path

import numpy as np
from google.protobuf.message import Message
from mcap.writer import Writer
from mcap_protobuf.schema import build_file_descriptor_set

from dgmm.errors import InputError
from dgmm.files import temporary_path
from dgmm.recording.output import Output

TICK_NS = 1_000_000
"""Log-time step between consecutive MCAP messages, in nanoseconds (1 ms, counted from the Unix epoch)."""


def _json_default(value):
    """Make numpy scalars and arrays JSON-serialisable."""
    if isinstance(value, (np.generic, np.ndarray)):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


class McapWriter(Output):
    """An MCAP file, each topic a channel, written atomically.

    A protobuf message (Foxglove's maintained types, ``foxglove_schemas_protobuf``) is written with its
    ``protobuf`` schema, named by its full name (``foxglove.SceneUpdate``); a dict is written as JSON under a JSON
    schema. Message ``n`` of the file is logged at ``n * TICK_NS`` nanoseconds unless told otherwise, so the same
    messages give the same bytes. Use as a context manager: on a clean exit the file is renamed into place, on an
    exception it is removed.

    Parameters
    ----------
    path : str or path-like
        Final file name; the data go to a temporary file beside it until :meth:`close`.

    Examples
    --------
    >>> with McapWriter("fit.mcap") as out:                                    # doctest: +SKIP
    ...     out.write("/fit/params", {"n_components": 25}, FIT_PARAMS_SCHEMA)
    ...     out.write("/fit/mixture", ellipsoid_scene_update(means, covariances, log_time_ns=out.next_log_time()))
    """

    def __init__(self, path):
        self.path = Path(path)
        self._temporary = temporary_path(self.path)
        self._stream = None
        try:  # an interrupt before __init__ returns would leave the caller nothing to abort
            self._stream = open(self._temporary, "wb")
            self._writer = Writer(self._stream)
            self._writer.start(profile="", library="dgmm")
        except BaseException:
            self.abort()
            raise
        self._schema_ids = {}
        self._channels = {}
        self._n_messages = 0

    def next_log_time(self):
        """Log time (ns) that :meth:`write` gives the next message by default."""
        return self._n_messages * TICK_NS

    def _schema_id(self, name, encoding, data):
        """Id of the schema record ``name``, registered on first use."""
        if name not in self._schema_ids:
            self._schema_ids[name] = self._writer.register_schema(name=name, encoding=encoding, data=data)
        return self._schema_ids[name]

    def write(self, topic, message, schema=None, log_time_ns=None):
        """Write one message on ``topic``; the topic's channel and the message's schema are registered on first
        use.

        Parameters
        ----------
        topic : str
        message : google.protobuf.message.Message or dict
            A protobuf message, or a JSON-serialisable dict (numpy scalars and arrays allowed; NaN and infinity
            are rejected).
        schema : dict, optional
            JSON schema of a dict ``message``, with a ``title`` naming it (``dgmm.FitIteration``); none for a
            protobuf message, which brings its own.
        log_time_ns : int, optional
            Defaults to :meth:`next_log_time`, so messages are evenly spaced in file order.
        """
        if log_time_ns is None:
            log_time_ns = self.next_log_time()
        if isinstance(message, Message):
            if schema is not None:
                raise InputError(f"MCAP topic {topic!r}: a protobuf message carries its own schema")
            name, encoding = message.DESCRIPTOR.full_name, "protobuf"
            data = message.SerializeToString(deterministic=True)
        else:
            name, encoding = schema["title"], "json"
            data = json.dumps(message, default=_json_default, allow_nan=False, separators=(",", ":")).encode()
        channel = self._channels.get(topic)
        if channel is None:
            if encoding == "protobuf":
                schema_id = self._schema_id(name, "protobuf",
                                            build_file_descriptor_set(type(message)).SerializeToString())
            else:
                schema_id = self._schema_id(name, "jsonschema", json.dumps(schema, sort_keys=True).encode())
            channel = self._channels[topic] = (self._writer.register_channel(topic, encoding, schema_id), name)
        elif channel[1] != name:
            raise InputError(f"MCAP topic {topic!r} carries {channel[1]!r} messages, not {name!r}")
        self._writer.add_message(channel[0], log_time=log_time_ns, data=data, publish_time=log_time_ns,
                                 sequence=self._n_messages)
        self._n_messages += 1

    def close(self):
        """Finish the file and rename it into place."""
        self._writer.finish()
        self._stream.close()
        os.replace(self._temporary, self.path)

    def abort(self):
        """Discard the file."""
        if self._stream is not None:
            self._stream.close()
        self._temporary.unlink(missing_ok=True)
