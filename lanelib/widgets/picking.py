"""The tuner's picker at work: reading the picked item (an image, or one frame of a video) and
showing it, and the camera calibration each item is seen through.

``Picking`` is a base class of ``base.Tuner`` that holds these methods apart from the tuner's
controls and preview. ``Tuner.__init__`` makes the state they use: the items (``images``), the
``picker`` and ``frame_slider`` widgets, the calibrations by camera (``_calibrations``) and the
video infos read so far (``_video_infos``). ``_pick`` hands the item it reads to the tuner's
hooks (``_prepare``, ``_update``) and refreshes the preview (``_refresh``).
"""
from __future__ import annotations

from pathlib import Path

from .. import io
from ..camera import Calibration
from ..data import udacity, udacity_calibration
from ..errors import CalibrationError, LaneLibError
from .choices import UDACITY_PREFIX, is_video


class Picking:
    """Read and show the item the picker (or the frame slider) picks; a subclass may override
    ``calibration_for`` (the camera of an item) and ``_on_frame`` (what a frame change does)."""

    def calibration_for(self, label: str) -> Calibration | None:
        """Return the calibration the picker's item ``label`` is undistorted with.

        Parameters
        ----------
        label : the item's label in the picker (a key of ``images``).

        Returns
        -------
        The Udacity camera's calibration for a ``udacity/...`` label (calibrated from its
        ``camera_cal/`` the first time one is asked for; None without those boards), else the
        calibration the tuner was given (None: frames are taken as undistorted).
        """
        camera = "udacity" if label.startswith(UDACITY_PREFIX) else "bundled"
        if camera not in self._calibrations:
            self._calibrations[camera] = udacity_calibration() if udacity("camera_cal") else None
        return self._calibrations[camera]

    def _on_pick(self, change) -> None:
        """Show the picked item; one that cannot be shown leaves the item before picked, and why."""
        if self._syncing:
            return
        frame = int(self.frame_slider.value)
        try:
            self._pick(change["new"])
        except LaneLibError as e:
            with self._quiet():
                self.picker.value = change["old"]
            self._pick(change["old"], frame)
            self._show_error(str(e))
            return
        self.error = ""

    def _on_frame(self, change) -> None:
        if not self._syncing and self.is_video:
            self._pick(self.image, int(change["new"]))

    def _video_info(self, path: Path) -> io.VideoInfo:
        """Return the VideoInfo of ``path``, read once per tuner."""
        if path not in self._video_infos:
            self._video_infos[path] = io.video_info(path)
        return self._video_infos[path]

    def _pick(self, label: str, frame: int = 0) -> None:
        """Show item ``label`` (at video frame ``frame``): read it, ``_prepare``, ``_update(None)``."""
        path = self.images[label]
        if is_video(path):
            info = self._video_info(path)
            frame = min(max(int(frame), 0), info.n_frames - 1)
            self._raw = io.read_frame(path, frame, info=info)
            with self._quiet():
                self.frame_slider.max = info.n_frames - 1
                self.frame_slider.value = frame
            self.frame_slider.layout.display = None
        else:
            self._raw = io.read_image(path)
            self.frame_slider.layout.display = "none"
        try:
            self._prepare(self._raw, self.calibration_for(label))
        except CalibrationError as e:
            raise CalibrationError(f"{path}: {e}; or, for frames of a camera without a calibration "
                                   "(CULane, TuSimple), make the tuner with calibration=None") from None
        self._update(None)
        self._refresh()
