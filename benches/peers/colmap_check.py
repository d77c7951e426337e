#!/usr/bin/env python3
"""Loads skytie's exported COLMAP text model (OUT/colmap/) with COLMAP's own reader (pycolmap) and reprojects
every 3-D point into every image that observes it with COLMAP's camera models (EQUIRECTANGULAR for the
panoramas, SIMPLE_RADIAL/OPENCV-type models for the aerial images). If skytie's export disagreed with COLMAP
about a pixel, axis or rotation convention, the reprojection errors would be pixels to hundreds of pixels.

Setup: python3 -m venv /tmp/colmap && /tmp/colmap/bin/pip install pycolmap numpy   (pycolmap >= 4: the
       EQUIRECTANGULAR camera model is COLMAP 4's)
Usage: /tmp/colmap/bin/python benches/peers/colmap_check.py OUT/colmap

Prints COLMAP's summary, then the reprojection-error quantiles (px) per camera model. The model holds every
observation of the adjustment, including those the robust adjustment rejected, so the largest errors are the
rejected outliers; the median is what shows whether the conventions agree.
"""
import sys

import numpy as np
import pycolmap


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    rec = pycolmap.Reconstruction(sys.argv[1])
    print(rec.summary())
    errors = {}
    for point in rec.points3D.values():
        for element in point.track.elements:
            image = rec.images[element.image_id]
            camera = rec.cameras[image.camera_id]
            cam_from_world = image.cam_from_world
            if callable(cam_from_world):  # pycolmap >= 3.12 made it a method
                cam_from_world = cam_from_world()
            projected = camera.img_from_cam(cam_from_world * point.xyz)
            observed = image.points2D[element.point2D_idx].xy
            error = float(np.linalg.norm(projected - observed))
            errors.setdefault(camera.model.name, []).append(error)
    print(f"{'camera model':<18} {'observations':>12} {'median px':>10} {'p90 px':>8} {'max px':>8}")
    for model, e in sorted(errors.items()):
        e = np.array(e)
        print(f"{model:<18} {len(e):>12} {np.median(e):>10.3f} {np.percentile(e, 90):>8.3f} {e.max():>8.2f}")


if __name__ == "__main__":
    main()
