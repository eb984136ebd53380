"""In-process pyrender rendering of object layers (coverage + camera-frame normals).

This module creates an OpenGL context in the *calling* process. A process that
forks after creating one deadlocks its children (Mesa/EGL state), so library
code does not use it directly: :class:`synthaug.render.server.Renderer` runs it
inside a private subprocess started with ``exec`` (never ``fork``). Use
:class:`GLLayerRenderer` directly only in a process that will not fork.

Normals are obtained by rendering the mesh unlit (``RenderFlags.FLAT``) with
each face coloured by its object-frame normal, ``c = (n + 1) / 2``; the
readback is decoded and rotated into the camera frame. Faces seen from behind
(inconsistent winding in coarse CAD models) are flipped toward the camera.
"""

from __future__ import annotations

import os

import numpy as np

CAMERA_DISTANCE = 3.0


def _select_platform() -> str:
    plat = os.environ.get("PYOPENGL_PLATFORM")
    if not plat:
        os.environ["PYOPENGL_PLATFORM"] = plat = "egl"
    return plat


class GLLayerRenderer:
    """Renders object layers of one mesh at given rotations/translations.

    Args:
        vertices: (V, 3) float, unit-size mesh.
        faces: (F, 3) int.
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray) -> None:
        self.platform = _select_platform()
        import pyrender  # noqa: WPS433 - GL import only where rendering happens
        import trimesh

        self._pyrender = pyrender
        mesh = trimesh.Trimesh(np.asarray(vertices, np.float64), np.asarray(faces, np.int64), process=False)
        normals = np.asarray(mesh.face_normals, dtype=np.float64)
        colors = np.clip(np.round((normals + 1.0) * 0.5 * 255.0), 0, 255).astype(np.uint8)
        mesh.visual = trimesh.visual.ColorVisuals(mesh, face_colors=np.concatenate(
            [colors, np.full((len(colors), 1), 255, np.uint8)], axis=1))
        self._mesh = pyrender.Mesh.from_trimesh(mesh, smooth=False)
        self._scene = pyrender.Scene(bg_color=[0.0, 0.0, 0.0, 0.0], ambient_light=[1.0, 1.0, 1.0])
        self._node = self._scene.add(self._mesh)
        self._cam_node = None
        self._offscreen = None

    def _renderer(self, size: int):
        # one context for the scene (pyrender binds meshes to a context); resize its viewport
        if self._offscreen is None:
            self._offscreen = self._pyrender.OffscreenRenderer(size, size)
        elif self._offscreen.viewport_width != size or self._offscreen.viewport_height != size:
            self._offscreen.viewport_width = size
            self._offscreen.viewport_height = size
        return self._offscreen

    def _set_camera(self, scale: float) -> None:
        mag = 0.5 / scale
        cam = self._pyrender.OrthographicCamera(xmag=mag, ymag=mag, znear=0.05, zfar=2 * CAMERA_DISTANCE + 2)
        if self._cam_node is not None:
            self._scene.remove_node(self._cam_node)
        pose = np.eye(4)
        pose[2, 3] = CAMERA_DISTANCE
        self._cam_node = self._scene.add(cam, pose=pose)

    def render(
        self,
        rotations: np.ndarray,
        translations: np.ndarray | None,
        *,
        size: int,
        scale: float,
        supersample: int = 2,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Render N views.

        Args:
            rotations: (N, 3, 3) object-to-camera rotations.
            translations: (N, 2) (t_x, t_y) in fractions of the patch side
                (image convention, y down), or None for centred.
            size: output side in pixels.
            scale: the mesh's unit length as a fraction of the patch side.
            supersample: render at ``size * supersample`` and box-average.

        Returns:
            coverage (N, size, size) float32 in [0, 1];
            normals (N, 3, size, size) float32, camera frame, unit where covered.
        """
        pyrender = self._pyrender
        n = len(rotations)
        hi = size * supersample
        renderer = self._renderer(hi)
        self._set_camera(scale)
        cov = np.zeros((n, size, size), np.float32)
        nrm = np.zeros((n, 3, size, size), np.float32)
        flags = pyrender.RenderFlags.FLAT | pyrender.RenderFlags.SKIP_CULL_FACES
        for i in range(n):
            pose = np.eye(4)
            pose[:3, :3] = rotations[i]
            if translations is not None:
                pose[0, 3] = translations[i][0] / scale
                pose[1, 3] = -translations[i][1] / scale
            self._scene.set_pose(self._node, pose)
            color, depth = renderer.render(self._scene, flags=flags)
            covered = depth > 0
            n_obj = color[..., :3].astype(np.float32) / 255.0 * 2.0 - 1.0
            n_cam = n_obj @ np.asarray(rotations[i], np.float32).T
            flip = n_cam[..., 2:3] < 0
            n_cam = np.where(flip, -n_cam, n_cam) * covered[..., None]
            c = covered.reshape(size, supersample, size, supersample).mean(axis=(1, 3))
            s = n_cam.reshape(size, supersample, size, supersample, 3).sum(axis=(1, 3))
            norm = np.linalg.norm(s, axis=-1, keepdims=True)
            s = np.where(norm > 1e-6, s / np.maximum(norm, 1e-6), 0.0)
            cov[i] = c
            nrm[i] = s.transpose(2, 0, 1)
        return cov, nrm

    def close(self) -> None:
        if self._offscreen is not None:
            self._offscreen.delete()
            self._offscreen = None
