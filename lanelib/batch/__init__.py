"""Batch runs of every pipeline: a folder of images, a video frame by frame, and the predictions
on a benchmark's labelled frames; in one process or on Dask (``workers``/``scheduler``,
``cluster.dask_client``).

The modules, by job:

- ``images``: a folder of images (``run_images``), its rows and ``results.json``;
- ``video``: a video in one process (``run_video``), the span of a clip (``clip_frames``), the
  per-frame CSV log, ``VideoRun``;
- ``segments``: a video in segments on Dask workers, joined into the output of one process
  (``run_video_segments``, ``video_segment``, ``FrameState``; ``join_videos`` joins the parts);
- ``geometry``: the road geometry of a run's input (``sample_frames``,
  ``estimate_road_geometry``, ``with_geometry``, ``road_geometry_run``);
- ``pipelines``: the advanced and the basic Hough pipeline on those (``process_images``,
  ``process_video``, ``hough_images``, ``hough_video``);
- ``predict``: the benchmark predictions (``predict_benchmark``) and the config they are made with
  by default (``benchmark_config``);
- ``refine``: a sequence's bird's-eye points moved to where the lines of its frames meet
  (``refine_points``, ``PointsRefinement``), for a camera mounted otherwise than the preset's.

Bad inputs: in a folder run, a file that cannot be read or processed (a lanelib error) gets its
own row with an ``error`` and the run goes on; a video that breaks off half-way keeps the frames
processed before the break and raises ``PartialOutputError`` once its outputs are in place.
"""
from .geometry import estimate_road_geometry, road_geometry_run, sample_frames, with_geometry
from .images import GRAYSCALE_NOTE, ImageFn, image_notes, run_images
from .pipelines import (VIDEO_LOG_COLUMNS, carry_lane_state, hough_images, hough_log_row, hough_video,
                        lane_image_process, lane_video_process, plan_lane_restarts, process_images,
                        process_video, video_log_row)
from .predict import (PREDICT_BENCHMARKS, PREDICT_SETTINGS, TUSIMPLE_PARTS, TUSIMPLE_PREDICTIONS,
                      FrameOutcome, FrameWork, GeometryFallback, PredictRun, benchmark_config,
                      benchmark_work, frame_sequence, predict_benchmark, predict_frame, seen_lines)
from .refine import PointsRefinement, refine_points
from .segments import FrameState, SegmentOutcome, run_video_segments, video_segment
from .video import FrameFn, VideoRun, clip_frames, run_video

__all__ = ["process_images", "process_video", "hough_images", "hough_video", "predict_benchmark",
           "run_images", "run_video", "run_video_segments", "video_segment", "clip_frames",
           "estimate_road_geometry", "road_geometry_run", "sample_frames", "with_geometry", "image_notes",
           "lane_image_process", "lane_video_process", "carry_lane_state", "plan_lane_restarts",
           "video_log_row", "hough_log_row", "benchmark_config", "benchmark_work", "frame_sequence",
           "predict_frame", "seen_lines", "VideoRun", "FrameState", "SegmentOutcome", "FrameWork", "FrameOutcome",
           "GeometryFallback", "PredictRun", "PointsRefinement", "refine_points", "ImageFn", "FrameFn",
           "GRAYSCALE_NOTE",
           "VIDEO_LOG_COLUMNS", "PREDICT_BENCHMARKS", "PREDICT_SETTINGS", "TUSIMPLE_PARTS",
           "TUSIMPLE_PREDICTIONS"]
