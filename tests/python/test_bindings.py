"""The Python module against the library and the `groundslam` program (run by `make test` through ctest).

Environment: PYTHONPATH holds the built module; GROUNDSLAM_BINARY is the program; GROUNDSLAM_TEST_DIR a scratch folder.
"""
import math
import os
import pathlib
import subprocess

import numpy as np
import pytest

import groundslam

BINARY = os.environ["GROUNDSLAM_BINARY"]
WORK = pathlib.Path(os.environ["GROUNDSLAM_TEST_DIR"])


@pytest.fixture(scope="module")
def sequence():
    """A 60-frame simulated loop on disk, and the program's run over it."""
    WORK.mkdir(parents=True, exist_ok=True)
    seq = WORK / "seq"
    if not (seq / "sequence.txt").exists():
        subprocess.run([BINARY, "simulate", str(seq), "--frames", "60", "--seed", "5"], check=True, capture_output=True)
    run = WORK / "run"
    subprocess.run(["rm", "-rf", str(run)], check=True)
    subprocess.run([BINARY, "run", str(seq / "sequence.txt"), "--out", str(run)], check=True, capture_output=True)
    return seq, run


def images_of(seq):
    dataset = groundslam.open_dataset(str(seq / "sequence.txt"))
    assert dataset.camera_yaml.endswith("camera.yaml")
    return [frame.image_path for frame in dataset.frames]


def test_config_defaults_and_yaml(sequence):
    seq, _ = sequence
    defaults = groundslam.Config()
    assert defaults.camera.image_width == 0  # required keys start unset
    config = groundslam.Config.from_yaml(str(seq / "camera.yaml"))
    assert (config.camera.image_width, config.camera.image_height) == (320, 240)
    config.camera.fx = 123.5  # settable from Python
    assert config.camera.fx == 123.5
    config.camera.fx = 0.0
    with pytest.raises(ValueError, match="camera.fx"):
        config.validate()
    with pytest.raises(ValueError):
        groundslam.Slam(config)
    assert config.camera.distortion_model == "radtan"
    config.camera.distortion_model = "equidistant"
    assert "distortion_model: equidistant" in config.to_yaml()
    with pytest.raises(ValueError, match="radtan, equidistant"):
        config.camera.distortion_model = "fisheye"
    config.vocabulary = "/somewhere/floor.gslmvoc"  # an input setting, written with the rest
    assert "vocabulary: /somewhere/floor.gslmvoc" in config.to_yaml()
    assert groundslam.default_config().endswith("default.yaml")
    assert groundslam.Config.from_yaml(groundslam.default_config()).camera.fx > 0


def test_same_trajectory_as_the_program(sequence):
    seq, run = sequence
    config = groundslam.Config.from_yaml(str(seq / "camera.yaml"))
    slam = groundslam.Slam(config)
    statuses = []
    for i, path in enumerate(images_of(seq)):
        image = groundslam.load_image(str(path), 320, 240)
        assert image.dtype == np.uint8 and image.shape == (240, 320)
        result = slam.process(image, float(i))
        statuses.append(result.status)
        assert isinstance(result.pose.x, float)
    slam.finish()
    trajectory = slam.trajectory()
    assert trajectory.shape == (60, 4) and trajectory.dtype == np.float64
    assert statuses[0] == "first" and statuses.count("ok") == 59
    # The program's trajectory.tum: timestamp x y z qx qy qz qw, 9 significant digits or more.
    tum = np.loadtxt(run / "trajectory.tum")
    assert np.allclose(trajectory[:, 0], tum[:, 0])
    assert np.allclose(trajectory[:, 1:3], tum[:, 1:3], atol=1e-6)
    heading = 2.0 * np.arctan2(tum[:, 6], tum[:, 7])
    assert np.allclose(np.angle(np.exp(1j * (trajectory[:, 3] - heading))), 0.0, atol=1e-6)


def test_simulator_and_tracking_accuracy():
    sim = groundslam.Simulator(texture="carpet", path="loop", frames=40, seed=9)
    assert sim.frame_count == 40
    truth = sim.ground_truth()
    slam = groundslam.Slam(sim.config())
    for i in range(sim.frame_count):
        slam.process(sim.render(i), float(i))
    slam.finish()
    estimate = slam.trajectory()
    # The estimate starts at the origin facing +x; the truth in the first pose's frame: after 40 frames (0.4 m)
    # every pose is within a few millimetres.
    x0, y0, t0 = truth[0, 1:]
    c, s = math.cos(t0), math.sin(t0)
    dx, dy = truth[:, 1] - x0, truth[:, 2] - y0
    relative = np.column_stack([c * dx + s * dy, -s * dx + c * dy, truth[:, 3] - t0])
    error = np.hypot(*(estimate[:, 1:3] - relative[:, :2]).T)
    assert error.max() < 0.005, error.max()
    assert abs(math.remainder(estimate[-1, 3] - relative[-1, 2], 2 * math.pi)) < math.radians(0.5)


def test_pipelined_slam_gives_the_same_results_one_frame_late(sequence):
    seq, _ = sequence
    config = groundslam.Config.from_yaml(str(seq / "camera.yaml"))
    images = [groundslam.load_image(str(path), 320, 240) for path in images_of(seq)]
    direct = groundslam.Slam(config)
    expected = [direct.process(image, float(i)).status for i, image in enumerate(images)]
    direct.finish()
    slam = groundslam.Slam(config)
    pipelined = groundslam.PipelinedSlam(slam)
    results = [pipelined.push(image, float(i)) for i, image in enumerate(images)]
    assert results[0] is None
    statuses = [r.status for r in results[1:]] + [pipelined.finish().status]
    assert statuses == expected
    assert np.array_equal(slam.trajectory(), direct.trajectory())


def test_bad_image_is_a_clear_error(sequence):
    seq, _ = sequence
    slam = groundslam.Slam(groundslam.Config.from_yaml(str(seq / "camera.yaml")))
    with pytest.raises(ValueError, match="2-D"):
        slam.process(np.zeros((240, 320, 3), dtype=np.uint8), 0.0)
    with pytest.raises(ValueError, match="missing.png"):
        groundslam.load_image(str(WORK / "missing.png"), 320, 240)
    with pytest.raises(ValueError, match="image is 640x480, the camera configuration says 320x240"):
        slam.process(np.zeros((480, 640), dtype=np.uint8), 0.0)
    odometry_only = groundslam.Config.from_yaml(str(seq / "camera.yaml"))
    odometry_only.loop_closure_enabled = False
    with pytest.raises(ValueError, match="loop closure"):
        groundslam.Slam(odometry_only).use_map(str(WORK / "whatever.gsmap"))


def test_map_save_and_reuse(sequence):
    seq, _ = sequence
    config = groundslam.Config.from_yaml(str(seq / "camera.yaml"))
    first = groundslam.Slam(config)
    paths = images_of(seq)
    for i, path in enumerate(paths):
        first.process(groundslam.load_image(str(path), 320, 240), float(i))
    first.finish()
    map_path = WORK / "session.gsmap"
    first.save_map(str(map_path))
    # One image at a time on the map, no pose prior: frame 30 where the first session put it.
    on_map = groundslam.Map(str(map_path), config)
    assert on_map.keyframes > 0
    found = on_map.localize(groundslam.load_image(str(paths[30]), 320, 240))
    assert found.ok and found.status == "localized", found.status
    assert math.hypot(found.pose.x - first.trajectory()[30][1], found.pose.y - first.trajectory()[30][2]) < 0.003
    blank = on_map.localize(np.full((240, 320), 128, dtype=np.uint8))
    assert not blank.ok
    second = groundslam.Slam(config)
    second.use_map(str(map_path))
    statuses = [second.process(groundslam.load_image(str(paths[i]), 320, 240), float(i)).status for i in range(30, 46)]
    second.finish()
    # The second session starts lost, localizes on the map and then tracks: its poses are in the first session's
    # frame, where the same images had these poses.
    assert statuses[0] == "lost" and "relocalized" in statuses and statuses[-1] == "ok", statuses
    poses = second.trajectory()
    mapped = first.trajectory()[30:46]
    assert poses.shape == (16, 4)
    assert np.abs(poses[:, 1:3] - mapped[:, 1:3]).max() < 0.003
