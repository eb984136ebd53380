"""Ingest: videos + boxes (or images + COCO) -> per-video shards -> seed sets.

Two stages, both restartable:

1. **Shards.** Every video (or chunk of COCO images) is processed on its own,
   in parallel worker processes, into ``OUT/pool/<stem>/``, itself a seed set
   (:mod:`synthaug.data.seedset`) holding that video's seed candidates
   (evenly spaced labelled frames, with backgrounds from
   :mod:`synthaug.data.backgrounds`), its background negatives and, for
   hard-negative classes (birds), its hard negatives. A shard is written to a
   temporary folder and renamed into place, so an interrupted run leaves no
   half-written shard. Each shard records the fingerprint of its inputs (the
   options, the video file's size and SHA-256 (not its time stamp: a copied
   folder keeps its shards), the label file's SHA-256, the split, the synthaug version); a rerun
   skips shards whose fingerprint is current and redoes the rest, with a
   warning naming what changed (so editing one label file re-ingests exactly
   that video). A video that fails writes ``OUT/pool/<stem>.error.json``
   with the reason and never stops the others. Worker processes die with the
   command (:mod:`synthaug._procs`): a ``kill -9`` leaves nothing running.
2. **Seed sets.** For every positive class and every requested count (12, 25,
   50, 100...), seeds are drawn from the *train* shards only, spread across
   videos (round-robin over the videos in a seeded order, so the 12-seed set is
   contained in the 25-seed set, and so on), into
   ``OUT/seedsets/<class>_<count>/`` with a ``contact_sheet.png``. Negatives of
   a seed set are all background negatives of that class's train videos plus
   the hard negatives of the train hard-negative videos. Seed sets are drawn
   from this run's shards only (not from shards of other videos an earlier run
   left in the pool), and record the run's fingerprint; a seed set under
   ``OUT/seedsets`` left by an earlier run with other inputs is reported as
   stale (``stale_seed_sets``), never as current.

``OUT/ingest_report.json`` sums up what was done, skipped, failed, repaired.

One module a stage: :mod:`.shards` (the options, a shard's inputs and freshness, making one),
:mod:`.seedsets` (drawing the seed sets) and :mod:`.run` (the commands, their worker processes and report).
"""

from __future__ import annotations

from synthaug.data.ingest.run import ingest_coco, ingest_videos
from synthaug.data.ingest.seedsets import assemble_seed_sets, select_spread, stale_seed_sets
from synthaug.data.ingest.shards import (
    SHARD_VERSION,
    IngestConfig,
    VideoJob,
    images_inputs,
    process_images,
    process_video,
    video_inputs,
)

__all__ = ["IngestConfig", "VideoJob", "process_video", "process_images", "ingest_videos", "ingest_coco",
           "assemble_seed_sets", "select_spread", "stale_seed_sets", "video_inputs", "images_inputs", "SHARD_VERSION"]
