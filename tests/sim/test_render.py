"""The video's caption (sim.render): drawn across the top of a copy of the frame, in the mode's colour."""

import numpy as np


def test_a_caption_is_drawn_across_the_top_of_a_frame():
    from sim.render import Caption
    from sim.task.eating import MODE_COLOURS

    img = np.full((480, 640, 3), 200, dtype=np.uint8)
    out = Caption(["t = 1.0 s", "robot leads (alpha 1.00)", "cutting"], MODE_COLOURS["cutting"]).draw(img)
    assert out.shape == img.shape and (img == 200).all()  # drawn on a copy
    banner, below = out[:30], out[60:]
    assert (banner == 20).all(axis=2).mean() > 0.5 and (banner == 255).all(axis=2).any()  # dark, white text
    assert (np.abs(banner.astype(int) - [0xC4, 0x4E, 0x52]).sum(axis=2) == 0).any()  # the mode's colour
    assert (below == 200).all()
