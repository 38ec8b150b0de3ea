"""Reading captures and images; writing images, GIFs and sidecars with lfproc's metadata.

Reading
    `read_capture` turns a sensor capture into a linear float32 `Capture`: Lytro containers
    (``.lfp``/``.lfr``) and raw pairs (``NAME.raw`` + ``NAME.txt``/``.json``) with their own levels
    and Bayer layout; camera raws (DNG, CR2, NEF, ARW, RAF, ORF, RW2, …) through LibRaw (rawpy),
    which carries its own black and white levels and CFA pattern; TIFF, PNG, EXR and every other
    format through OpenImageIO, with the levels and CFA of the camera file. `read_image` reads any
    image as stored, for general use. `read_lytro_metadata` parses a Lytro file's metadata
    (`LytroMetadata`); `describe_file` says what any file is and holds (``lfproc info``);
    `lytro_camera` builds a `Camera` from Lytro metadata; `pick_white_image` picks a white image
    from a calibration folder. Processed pictures (focus stacks, depth maps, perspective views; no raw
    frame): `open_picture` (a `LytroPicture`), `depth_lambda`, `confidence_map`, `picture_metadata`,
    `camera_metadata` (any Lytro file), `is_picture_file` and `refuse_pictures` (cheap, headers only);
    `lambda_map` turns Lytro's lambda into the paper's a and distances (`LambdaMap`;
    `camera_lambda_map` from a camera file, `refocused_map` for a picture's refocused focus; `focused_at`: a
    camera with its main lens focused at a distance);
    `stack_images` decodes a picture's focus stack and `encode_jpeg` re-encodes a frame.
    `is_napari_metadata` and `napari_camera` read napari-LF's ``metadata.txt`` as a microscope camera;
    `read_camera` reads any of the three files that describe a camera (a camera TOML, napari-LF's
    ``metadata.txt``, a Lytro file's metadata).
    `decode_picture_views` decodes a picture's H.264 perspective views; `is_container` and
    `has_container_extension` tell a Lytro container by its bytes and its name; `existing_file` checks a
    path names a readable file (one-line error); `libraries_quiet` keeps what the image libraries print
    themselves off stderr (every reader calls them inside it).

Writing
    `write_image` writes float32 linear images as float TIFF (the default for outputs), 16-bit
    linear PNG, float EXR or 8-bit sRGB JPEG (for viewing only), and uint16 sensor data exactly,
    with lfproc's metadata dict embedded (see ``_write.py`` for what each format keeps). The JSON
    sidecar (`write_sidecar`, contract: ``NAME.EXT`` -> ``NAME.json``) holds the same dict for every
    format. `write_gif` writes animated previews of linear frames; `write_png_preview` and
    `write_gif_frames` write 8-bit pictures for people with lfproc's tags embedded, `label_font` and
    `label_text` draw their labels (with µ where a font has it; ``_preview.py``). All
    writers are atomic.

OpenImageIO, rawpy and Pillow are imported inside the functions that use them, so importing this
package is cheap (numpy only).

Internal package: not lfproc's API (docs/api.md lists that); its names serve lfproc's own stages, commands and
tests, and may change without notice.
"""

from ._camera_file import read_camera
from ._capture import Capture
from ._checks import existing_file
from ._describe import describe_file
from ._gif import write_gif
from ._libraw import bayer_pattern_from_colors
from ._lytro_camera import lytro_camera
from ._lytro_container import has_container_extension, is_container
from ._lytro_h264 import decode_views as decode_picture_views
from ._lytro_lambda import camera_lambda_map, focused_at, lambda_map, refocused_map
from ._lytro_picture_open import (camera_metadata, is_picture_file, open_picture, picture_lambda_map,
                                  picture_metadata, refuse_pictures)
from ._lytro_picture_pixels import confidence_map, depth_lambda, encode_jpeg, stack_images
from ._lytro_read import is_lytro_file, read_lytro, read_lytro_metadata
from ._lytro_unpack import unpack_raw
from ._lytro_white import check_white_matches, pick_white_image
from ._napari_metadata import is_napari_metadata, napari_camera
from ._native import libraries_quiet
from ._oiio import read_image
from ._preview import label_font, label_text, write_gif_frames, write_png_preview
from ._read import read_capture
from ._sidecar import sidecar_path, write_sidecar
from ._write import FORMATS, read_metadata, srgb_decode, srgb_encode, write_image
