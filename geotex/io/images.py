"""Texture images of mesh files: read one (bounded in pixels) and encode one as PNG."""

from __future__ import annotations

import numpy as np
from PIL import Image

from geotex.io.limits import MAX_TEXTURE_PIXELS, RefusedInput

__all__ = ["load_texture_image", "texture_to_png_bytes"]


def load_texture_image(source) -> np.ndarray:
    """Read an image file or file object as an ``(h, w, 3 or 4)`` uint8 array.

    Raises any pillow / OS error, or :class:`geotex.io.limits.RefusedInput`
    for an image above :data:`~geotex.io.limits.MAX_TEXTURE_PIXELS`; callers
    decide whether that is fatal.
    """
    with Image.open(source) as img:
        width, height = img.size
        if width * height > MAX_TEXTURE_PIXELS:
            raise RefusedInput(f"texture image of {width} x {height} pixels is larger "
                               f"than the {MAX_TEXTURE_PIXELS} pixels allowed")
        img.load()
        has_alpha = img.mode in ("RGBA", "LA", "PA") or (
            img.mode == "P" and "transparency" in img.info)
        img = img.convert("RGBA" if has_alpha else "RGB")
        return np.ascontiguousarray(np.asarray(img, dtype=np.uint8))


def texture_to_png_bytes(texture: np.ndarray) -> bytes:
    """Encode an ``(h, w, 3 or 4)`` uint8 texture as PNG."""
    import io

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(texture)).save(buf, format="PNG")
    return buf.getvalue()
