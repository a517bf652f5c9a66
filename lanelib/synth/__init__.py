"""Synthetic camera, chessboards and road scenes with exact ground truth.

``generate_all(out_root)`` writes the bundled data (``camera_cal/``, ``test_images/``,
``videos/``) from fixed seeds (the same bytes on one machine; see ``sets``); ``python -m lanelib synth --all`` calls it.
The truth beside every file is read back with ``load_image_truth``, ``load_video_truth`` and
``load_board_truth``. See ``truth`` for the file formats and sign conventions.
``Camera.pinhole`` makes other cameras (any size, focal length, mounting and roll) for
``GroundGrid.build``; ``Renderer.for_grid`` renders a scene through another camera without
drawing its maps again; ``CameraTruth`` and ``birdseye_scale`` give their true road geometry.
``datasets.write_dataset`` renders a sample in the TuSimple or CULane layout with exact labels
(``python -m lanelib synth dataset``).
"""
from .camera import Camera
from .render import GroundGrid, Renderer
from .road import CarPose, CurvatureProfile
from .scene import Bridge, Layout, Look, Scene, Streak
from .sets import generate_all, image_scenes, video_sets, write_boards, write_test_images, write_video
from .truth import (BoardTruth, CameraTruth, ImageTruth, LaneTruth, PerspectiveTruth, VideoTruth,
                    birdseye_scale, camera_truth, lane_truth, load_board_truth, load_image_truth,
                    load_video_truth, perspective_truth)

__all__ = [
    "Camera", "GroundGrid", "Renderer", "CarPose", "CurvatureProfile", "Bridge", "Layout", "Look",
    "Scene", "Streak", "generate_all", "image_scenes", "video_sets", "write_boards",
    "write_test_images", "write_video", "BoardTruth", "CameraTruth", "ImageTruth", "LaneTruth",
    "PerspectiveTruth", "VideoTruth", "lane_truth", "load_board_truth", "load_image_truth",
    "load_video_truth", "perspective_truth", "birdseye_scale", "camera_truth",
]
