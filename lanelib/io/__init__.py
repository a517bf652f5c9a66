"""Reading and writing images, reading videos, and atomic output files.

Images are RGB ``uint8`` arrays (H x W x 3) everywhere in lanelib; BGR exists only inside this
package. Videos go through imageio-ffmpeg. Outputs are written atomically and never over an input.

- ``images``: image files read as RGB arrays (``read_image``, ``read_image_info``), the frame
  check every stage runs (``check_rgb``), encoding and writing (``encode_image``,
  ``write_image``), a folder's images (``list_images``);
- ``files``: atomic outputs (``atomic_path``, ``check_output``, ``remove_stale_temp_files``),
  text and JSON (``write_text``, ``write_json``, ``read_json``);
- ``video``: videos read frame by frame or by seeking (``VideoReader``, ``read_frame``,
  ``video_info``); ``batch.video.VideoWriter`` writes them.

Their public names, and the errors they raise, are names of this package too (``io.read_image``).
"""
from ..errors import DecodeStoppedError, InputError
from .files import (atomic_path, check_not_input, check_output, read_json, remove_stale_temp_files,
                    write_json, write_text)
from .images import (IMAGE_SUFFIXES, PIPELINE_SIZE_FIX, ImageFileInfo, captured_native_stderr,
                     check_rgb, encode_image, list_images, read_image, read_image_info, write_image)
from .video import (SHORTFALL_FRAMES, SHORTFALL_SHARE, VIDEO_SUFFIXES, VideoInfo, VideoReader, exact_fps,
                    ffmpeg_cause, read_frame, video_info)

__all__ = ["IMAGE_SUFFIXES", "ImageFileInfo", "captured_native_stderr", "read_image_info", "read_image",
           "PIPELINE_SIZE_FIX", "check_rgb", "encode_image", "write_image", "list_images",
           "check_not_input", "check_output", "remove_stale_temp_files", "atomic_path", "write_text",
           "write_json", "read_json",
           "VIDEO_SUFFIXES", "VideoInfo", "SHORTFALL_FRAMES", "SHORTFALL_SHARE", "ffmpeg_cause",
           "VideoReader", "video_info", "exact_fps", "read_frame",
           "InputError", "DecodeStoppedError"]
