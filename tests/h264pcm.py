"""A minimal H.264 (Annex B) writer for the tests: every macroblock I_PCM, so no encoder is needed.

The pip OpenCV wheel decodes H.264 (FFmpeg's decoder) but has no H.264 encoder (only a hardware
``h264_v4l2m2m`` that finds no device), so ``cv2.VideoWriter`` cannot write the stream an
``edofParallax`` block holds. I_PCM macroblocks (ITU-T H.264 7.3.5: ``mb_type`` 25 in an I slice)
carry their samples verbatim, so a valid stream is a bit writer away: one SPS (Baseline profile,
7.3.2.1.1), one PPS (7.3.2.2), then one IDR picture per frame, each a single slice (7.3.3) of I_PCM
macroblocks, with emulation prevention (7.4.1). Frames are YCbCr 4:2:0, sizes multiples of 16.
"""

from __future__ import annotations

import numpy as np


class _Bits:
    def __init__(self):
        self.bits: list[int] = []

    def u(self, n: int, value: int) -> None:
        self.bits += [(value >> (n - 1 - i)) & 1 for i in range(n)]

    def ue(self, value: int) -> None:
        code = value + 1
        length = code.bit_length()
        self.u(length - 1, 0)
        self.u(length, code)

    def se(self, value: int) -> None:
        self.ue(2 * value - 1 if value > 0 else -2 * value)

    def align_zero(self) -> None:
        while len(self.bits) % 8:
            self.bits.append(0)

    def raw_bytes(self, data: bytes) -> None:
        assert len(self.bits) % 8 == 0
        for byte in data:
            self.u(8, byte)

    def trailing(self) -> bytes:
        self.bits.append(1)
        self.align_zero()
        array = np.packbits(np.array(self.bits, np.uint8))
        return array.tobytes()


def _nal(nal_byte: int, rbsp: bytes) -> bytes:
    """Start code, NAL header byte, RBSP with emulation prevention (00 00 0x → 00 00 03 0x for x ≤ 3)."""
    out = bytearray()
    zeros = 0
    for byte in rbsp:
        if zeros >= 2 and byte <= 3:
            out.append(3)
            zeros = 0
        out.append(byte)
        zeros = zeros + 1 if byte == 0 else 0
    return b"\x00\x00\x00\x01" + bytes([nal_byte]) + bytes(out)


def _sps(width_mbs: int, height_mbs: int) -> bytes:
    b = _Bits()
    b.u(8, 66)          # profile_idc: Baseline
    b.u(8, 0)           # constraint flags + reserved
    b.u(8, 30)          # level_idc 3.0
    b.ue(0)             # seq_parameter_set_id
    b.ue(0)             # log2_max_frame_num_minus4
    b.ue(2)             # pic_order_cnt_type 2: output order = decoding order
    b.ue(1)             # max_num_ref_frames
    b.u(1, 0)           # gaps_in_frame_num_value_allowed_flag
    b.ue(width_mbs - 1)
    b.ue(height_mbs - 1)
    b.u(1, 1)           # frame_mbs_only_flag
    b.u(1, 1)           # direct_8x8_inference_flag
    b.u(1, 0)           # frame_cropping_flag
    b.u(1, 0)           # vui_parameters_present_flag
    return _nal(0x67, b.trailing())


def _pps() -> bytes:
    b = _Bits()
    b.ue(0)             # pic_parameter_set_id
    b.ue(0)             # seq_parameter_set_id
    b.u(1, 0)           # entropy_coding_mode_flag: CAVLC
    b.u(1, 0)           # bottom_field_pic_order_in_frame_present_flag
    b.ue(0)             # num_slice_groups_minus1
    b.ue(0)             # num_ref_idx_l0_default_active_minus1
    b.ue(0)             # num_ref_idx_l1_default_active_minus1
    b.u(1, 0)           # weighted_pred_flag
    b.u(2, 0)           # weighted_bipred_idc
    b.se(0)             # pic_init_qp_minus26
    b.se(0)             # pic_init_qs_minus26
    b.se(0)             # chroma_qp_index_offset
    b.u(1, 1)           # deblocking_filter_control_present_flag
    b.u(1, 0)           # constrained_intra_pred_flag
    b.u(1, 0)           # redundant_pic_cnt_present_flag
    return _nal(0x68, b.trailing())


def _idr_slice(y: np.ndarray, cb: np.ndarray, cr: np.ndarray, idr_pic_id: int) -> bytes:
    b = _Bits()
    b.ue(0)             # first_mb_in_slice
    b.ue(7)             # slice_type: I (all slices of the picture)
    b.ue(0)             # pic_parameter_set_id
    b.u(4, 0)           # frame_num (log2_max_frame_num = 4)
    b.ue(idr_pic_id)    # idr_pic_id: differs between consecutive IDR pictures
    b.u(1, 0)           # no_output_of_prior_pics_flag
    b.u(1, 0)           # long_term_reference_flag
    b.se(0)             # slice_qp_delta
    b.ue(1)             # disable_deblocking_filter_idc: off
    rows, cols = y.shape[0] // 16, y.shape[1] // 16
    for my in range(rows):
        for mx in range(cols):
            b.ue(25)    # mb_type I_PCM
            b.align_zero()      # pcm_alignment_zero_bit
            b.raw_bytes(y[16 * my:16 * my + 16, 16 * mx:16 * mx + 16].tobytes())
            b.raw_bytes(cb[8 * my:8 * my + 8, 8 * mx:8 * mx + 8].tobytes())
            b.raw_bytes(cr[8 * my:8 * my + 8, 8 * mx:8 * mx + 8].tobytes())
    return _nal(0x65, b.trailing())


def rgb_to_ycbcr(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """BT.601 limited-range YCbCr of 8-bit RGB ``(H, W, 3)``; chroma averaged over 2×2 blocks (4:2:0)."""
    r, g, b = (rgb[..., k].astype(np.float64) for k in range(3))
    y = 16 + (65.481 * r + 128.553 * g + 24.966 * b) / 255
    cb = 128 + (-37.797 * r - 74.203 * g + 112.0 * b) / 255
    cr = 128 + (112.0 * r - 93.786 * g - 18.214 * b) / 255

    def sub(c):
        return c.reshape(c.shape[0] // 2, 2, c.shape[1] // 2, 2).mean(axis=(1, 3))

    def byte(c):
        return np.clip(np.round(c), 1, 255).astype(np.uint8)   # PCM samples of 0 were once forbidden

    return byte(y), byte(sub(cb)), byte(sub(cr))


def h264_stream(frames_rgb) -> bytes:
    """An Annex B stream of 8-bit RGB frames (all the same size, multiples of 16), one IDR picture each."""
    frames_rgb = [np.asarray(f, np.uint8) for f in frames_rgb]
    height, width = frames_rgb[0].shape[:2]
    assert height % 16 == 0 and width % 16 == 0
    out = bytearray(_sps(width // 16, height // 16) + _pps())
    for k, frame in enumerate(frames_rgb):
        out += _idr_slice(*rgb_to_ycbcr(frame), idr_pic_id=k % 2)
    return bytes(out)
