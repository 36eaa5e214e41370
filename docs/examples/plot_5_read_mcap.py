"""
Read a fit's MCAP back
======================

Every fit can be recorded to an MCAP file (what ``dgmm fit --mcap`` and the workflow's fit jobs write). Here three
seeds of one fit are recorded with :class:`dgmm.recording.FitRecorder`, the estimator's ``callback``, and read
back with the ``mcap`` package's own reader: dgmm's outcomes are JSON messages (``/fit/params``,
``/fit/iteration``), the mixtures Foxglove's protobuf ``foxglove.SceneUpdate`` (``/fit/mixture``), which
``mcap-protobuf-support`` decodes from the schema stored in the file. Foxglove Studio opens the same file: its
3D panel draws ``/fit/mixture`` and its Plot panel ``/fit/iteration.bound``.
"""

import json
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
from mcap.decoder import DecoderFactory
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory as ProtobufDecoderFactory

import dgmm
from dgmm.data import REGISTRY, fetch, load_mesh
from dgmm.recording import FitRecorder

root = Path(dgmm.__file__).resolve().parents[1]
path = fetch(REGISTRY["bunny"]["res4"], mirrors=[root / "../shared/data/stanford"], cache=Path.home() / ".cache/dgmm")
mesh = dgmm.Primitives.from_mesh(*load_mesh(path))

folder = Path(tempfile.mkdtemp())
mcap_path = folder / "fit.mcap"
with FitRecorder(mcap_path, params={"n_components": 25, "init": "random"}) as recorder:
    for seed in range(3):
        recorder.begin_seed(seed)
        model = dgmm.GaussianMixture(25, init="random", max_iter=25, tol=0, random_state=seed, callback=recorder)
        recorder.end_seed(model.fit(mesh))
print(f"{mcap_path.name}: {mcap_path.stat().st_size} bytes")


# %%
# The mcap package ships no JSON decoder: a three-line factory gives one.
class JsonDecoderFactory(DecoderFactory):
    def decoder_for(self, message_encoding, schema):
        return json.loads if message_encoding == "json" else None


bounds = {}
with open(mcap_path, "rb") as stream:
    reader = make_reader(stream, decoder_factories=[ProtobufDecoderFactory(), JsonDecoderFactory()])
    for schema, channel, message, decoded in reader.iter_decoded_messages():
        if channel.topic == "/fit/params":
            print("params:", decoded)
        elif channel.topic == "/fit/iteration":
            bounds.setdefault(decoded["seed"], []).append(decoded["bound"])
        elif channel.topic == "/fit/mixture":
            entity = decoded.entities[0]
            print(f"{schema.name} {entity.id}: {len(entity.spheres)} ellipsoids, metadata "
                  + ", ".join(f"{pair.key}={pair.value}" for pair in entity.metadata))

# %%
fig, ax = plt.subplots(figsize=(6, 3.5))
for seed, values in bounds.items():
    ax.plot(range(1, len(values) + 1), values, marker=".", label=f"seed {seed}")
ax.set_xlabel("EM iteration")
ax.set_ylabel("bound (from /fit/iteration)")
ax.set_title("bunny res4, K=25 from random starts, read back from MCAP")
ax.legend()
fig.tight_layout()
