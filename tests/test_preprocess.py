"""The encoder's fixed frame transforms: Gaussian blur and frame differences."""

from __future__ import annotations

import pytest
import torch

from curiosity.nets import ConvEncoder
from curiosity.nets.preprocess import FrameDifferences, GaussianBlur


def test_blur_keeps_the_background_and_the_ink_of_a_dark_pixel():
    frames = torch.ones(2, 3, 32, 32)  # white background (1.0)
    frames[0, 1, 16, 16] = -1.0  # one black pixel: 2 units of ink below the background
    out = GaussianBlur(2.0, keep_contrast=False)(frames)
    assert out.shape == frames.shape
    torch.testing.assert_close(out[1], frames[1])  # a blank frame stays blank (padding is background)
    torch.testing.assert_close(out[0, 0], frames[0, 0])  # channels are blurred separately
    ink = (1.0 - out[0, 1]).sum()
    torch.testing.assert_close(ink, torch.tensor(2.0), rtol=1e-4, atol=1e-4)  # far from the border: no ink lost
    spread = 1.0 - out[0, 1]
    assert spread[16, 16] < 2.0 / 10 and spread[16, 18] > 0  # the dot is spread over its neighbours
    torch.testing.assert_close(spread, spread.T)  # isotropic kernel, symmetric about the dot


def test_blur_keeps_the_contrast_of_a_thin_line():
    frames = torch.ones(1, 1, 64, 64)
    frames[0, 0, :, 32] = 0.0  # a vertical line one pixel wide, one unit below the background
    for sigma in (1.5, 4.0):
        peak = 1.0 - GaussianBlur(sigma)(frames)[0, 0, 32, 32]
        assert peak == pytest.approx(1.0, abs=0.02)  # the sampled kernel's peak is 1/(√(2π)σ) to within 1 %
        dimmed = 1.0 - GaussianBlur(sigma, keep_contrast=False)(frames)[0, 0, 32, 32]
        assert dimmed == pytest.approx(1.0 / (2 * torch.pi) ** 0.5 / sigma, rel=0.02)


def test_blur_distance_grows_with_the_displacement_where_raw_frames_saturate():
    def bar(col: int) -> torch.Tensor:
        f = torch.ones(1, 1, 32, 32)
        f[0, 0, 8:24, col] = -1.0
        return f

    blur = GaussianBlur(3.0)
    raw = [torch.dist(bar(10), bar(10 + k)).item() for k in (1, 2, 4)]
    blurred = [torch.dist(blur(bar(10)), blur(bar(10 + k))).item() for k in (1, 2, 4)]
    assert raw[0] == pytest.approx(raw[2])  # thin lines: one pixel apart is as far as four
    assert blurred[0] < blurred[1] < blurred[2]


@pytest.mark.parametrize("sigma", [1.0, 4.0, 6.0])
@pytest.mark.parametrize("shape", [(5, 4, 32, 32), (2, 3, 64, 64), (1, 2, 8, 20)])
def test_blur_as_band_matrices_equals_the_two_padded_convolutions(sigma: float, shape: tuple[int, ...]):
    # the same sums in another order: equal to float rounding (tolerance), not bit for bit; frames smaller than the
    # kernel (8 x 20 with radius 18) included
    frames = torch.rand(shape, generator=torch.Generator().manual_seed(0)) * 2 - 1
    blur = GaussianBlur(sigma)
    torch.testing.assert_close(blur(frames), blur.reference(frames), rtol=1e-5, atol=1e-5)
    torch.testing.assert_close(blur(frames.double()), blur.reference(frames.double()), rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize("stride", [2, 3])
def test_a_strided_blur_is_the_full_blur_sampled_at_every_stride_th_pixel(stride: int):
    # the band matrices' rows 0, s, 2s, ... against the full blur's pixels and the strided padded convolutions:
    # equal to float rounding (tolerance), not bit for bit
    frames = torch.rand(3, 4, 32, 32, generator=torch.Generator().manual_seed(1)) * 2 - 1
    full, strided = GaussianBlur(4.0), GaussianBlur(4.0, stride=stride)
    out = strided(frames)
    assert out.shape == (3, 4, -(-32 // stride), -(-32 // stride))
    torch.testing.assert_close(out, full(frames)[..., ::stride, ::stride], rtol=1e-5, atol=1e-5)
    torch.testing.assert_close(out, strided.reference(frames), rtol=1e-5, atol=1e-5)


def test_blur_rejects_a_non_positive_sigma_or_stride():
    with pytest.raises(ValueError, match="sigma"):
        GaussianBlur(0.0)
    with pytest.raises(ValueError, match="stride"):
        GaussianBlur(4.0, stride=0)


def test_frame_differences_are_the_newest_frame_then_successive_differences():
    frames = torch.randn(3, 4, 8, 8)
    out = FrameDifferences(gain=2.0)(frames)
    torch.testing.assert_close(out[:, 0], frames[:, 3])
    torch.testing.assert_close(out[:, 1], 2.0 * (frames[:, 3] - frames[:, 2]))
    torch.testing.assert_close(out[:, 3], 2.0 * (frames[:, 1] - frames[:, 0]))
    # invertible: the oldest frame is recovered from the newest and the differences
    torch.testing.assert_close(out[:, 0] - out[:, 1:].sum(1) / 2.0, frames[:, 0], rtol=1e-5, atol=1e-5)


def test_conv_encoder_transforms_are_off_by_default_and_leave_the_state_dict_alone():
    plain, blurred = ConvEncoder(), ConvEncoder(blur_sigma=2.0, differences=True)
    assert len(plain.preprocess) == 0 and len(blurred.preprocess) == 2
    assert plain.state_dict().keys() == blurred.state_dict().keys()  # checkpoints load either way
    blurred.load_state_dict(plain.state_dict())
    x = torch.randn(5, 4, 32, 32)
    assert blurred(x).shape == (5, 4)
    expected = plain(FrameDifferences()(GaussianBlur(2.0)(x)))
    torch.testing.assert_close(blurred(x), expected, rtol=1e-5, atol=1e-6)
