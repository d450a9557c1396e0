"""mpm.render: the engine's renderer into a numpy image, and a PNG written beside."""

import numpy as np
import pytest

import mpm


def test_render_a_simulation_and_a_folder(tmp_path, scene):
    sim = mpm.Simulation(scene)
    with pytest.raises(mpm.Error, match="open_output"):
        mpm.render(sim)
    sim.open_output(str(tmp_path / "run"))
    sim.run(frames=2)
    image = mpm.render(sim, width=160, height=120, path=tmp_path / "last.png")
    assert image.shape == (120, 160, 3) and image.dtype == np.uint8
    assert (tmp_path / "last.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the block is drawn: the picture is not one colour, and the middle differs from a corner
    assert len(np.unique(image.reshape(-1, 3), axis=0)) > 20
    first = mpm.render(tmp_path / "run", frame=0, width=160, height=120, field="J",
                       legend=False, time_label=False)
    assert first.shape == (120, 160, 3) and not np.array_equal(first, image)
    with pytest.raises(mpm.Error):
        mpm.render(tmp_path / "run", frame=7)  # no such frame file
    with pytest.raises(OSError):  # a folder that is not there
        mpm.render(tmp_path / "nowhere")


def test_render_frames(tmp_path, scene):
    sim = mpm.Simulation(scene)
    sim.open_output(str(tmp_path / "run"))
    sim.run(frames=2)
    paths = mpm.render_frames(sim, tmp_path / "pictures", width=96, height=64)
    assert [p.rsplit("/", 1)[1] for p in paths] == ["frame_0000.png", "frame_0001.png",
                                                      "frame_0002.png"]
    for p in paths:
        with open(p, "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    assert len(mpm.render_frames(tmp_path / "run", tmp_path / "every2", width=96, height=64,
                                 every=2)) == 2
