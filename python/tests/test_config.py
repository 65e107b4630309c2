"""ssta.Config against the command line's config reader: the same values, checks and messages."""

import numpy as np
import pytest

import ssta
from conftest import cli_error


def test_defaults_are_the_cli_defaults(cli, tmp_path):
    # `ssta config` prints the defaults with comments; read back, they are Config()'s.
    (tmp_path / "printed.yaml").write_text(cli("config").stdout)
    assert ssta.Config.load(tmp_path / "printed.yaml").to_yaml() == ssta.Config().to_yaml()


def test_sections_are_every_section_of_the_yaml():
    config = ssta.Config()
    top_level = [line[:-1] for line in config.to_yaml().splitlines() if line and not line.startswith(" ")]
    assert config.sections() == top_level
    assert list(config.to_dict()) == top_level
    for name in top_level:
        section = getattr(config, name)
        assert section.keys() == list(section.to_dict())


def test_load_layers_files_as_the_cli(cli, tmp_path):
    (tmp_path / "a.yaml").write_text("vehicle:\n  max_slope_deg: 30\n  semi_slope_deg: 20\nmap:\n  resolution_m: 0.2\n")
    (tmp_path / "b.yaml").write_text("vehicle:\n  semi_slope_deg: 12\n")
    config = ssta.Config.load(tmp_path / "a.yaml", str(tmp_path / "b.yaml"))
    assert config.vehicle.max_slope_deg == 30.0
    assert config.vehicle.semi_slope_deg == 12.0
    assert config.map.resolution_m == 0.2
    printed = cli("config", "--config", tmp_path / "a.yaml", "--config", tmp_path / "b.yaml").stdout
    (tmp_path / "printed.yaml").write_text(printed)
    assert ssta.Config.load(tmp_path / "printed.yaml").to_yaml() == config.to_yaml()


@pytest.mark.parametrize("text", [
    "vehicle:\n  max_slope_deg: 95\n",      # out of range
    "vehicle:\n  max_slope_dge: 20\n",      # unknown key
    "vehicel:\n  max_slope_deg: 20\n",      # unknown section
    "stereo:\n  matcher: nonsense\n",       # not one of the choices
    "vehicle:\n  max_slope_deg: [1, 2]\n",  # wrong type
])
def test_bad_files_raise_the_cli_message(tmp_path, text):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ssta.Error) as e:
        ssta.Config.load(path)
    assert str(e.value) == cli_error("config", "--config", path)
    assert str(path) in str(e.value)


def test_missing_file_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError) as e:
        ssta.Config.load(tmp_path / "a.yaml", tmp_path / "missing.yaml")
    assert e.value.filename == str(tmp_path / "a.yaml")


def test_attributes_are_checked_as_file_values():
    config = ssta.Config()
    config.vehicle.max_slope_deg = 30
    assert config.vehicle.max_slope_deg == 30.0 and isinstance(config.vehicle.max_slope_deg, float)
    with pytest.raises(ValueError, match=r"^vehicle\.semi_slope_deg: must not exceed max_slope_deg"):
        config.vehicle.semi_slope_deg = 40.0
    assert config.vehicle.semi_slope_deg == 15.0  # left as it was
    with pytest.raises(ValueError, match=r"^vehicle\.max_step_m: must be a number, got 'high'"):
        config.vehicle.max_step_m = "high"
    with pytest.raises(ValueError, match=r"^map\.checkpoint_every_frames: must be a whole number \(int\), got 2\.5"):
        config.map.checkpoint_every_frames = 2.5
    with pytest.raises(ValueError, match=r"^map\.auto_range: must be True or False, got 1"):
        config.map.auto_range = 1
    with pytest.raises(ValueError, match=r"^map\.resolution_m: must be a number in"):
        config.map.resolution_m = -1.0
    with pytest.raises(AttributeError, match=r"^vehicle\.max_slope: unknown key \(vehicle has max_slope_deg, "):
        config.vehicle.max_slope = 3
    with pytest.raises(AttributeError):
        config.vehicle.max_slope  # noqa: B018


def test_choices_and_vectors_round_trip(tmp_path):
    config = ssta.Config()
    choice_key = next(k for k, v in config.analysis.to_dict().items() if isinstance(v, str))
    with pytest.raises(ValueError, match=rf"^analysis\.{choice_key}: must be one of "):
        setattr(config.analysis, choice_key, "nonsense")
    vector_sections = [(s, k) for s in config.sections() for k, v in getattr(config, s).to_dict().items()
                       if isinstance(v, tuple)]
    if vector_sections:
        section, key = vector_sections[0]
        setattr(getattr(config, section), key, np.array([0.0, 0.0, 1.0]))
        assert getattr(getattr(config, section), key) == (0.0, 0.0, 1.0)


def test_save_writes_yaml_that_loads_back(tmp_path):
    config = ssta.Config()
    config.vehicle.max_slope_deg = 28.5
    config.map.pixel_stride = 2
    config.save(tmp_path / "edited.yaml")
    again = ssta.Config.load(tmp_path / "edited.yaml")
    assert again.to_yaml() == config.to_yaml()
    assert again.vehicle.max_slope_deg == 28.5 and again.map.pixel_stride == 2


def test_copy_is_independent():
    a = ssta.Config()
    b = a.copy()
    b.vehicle.max_step_m = 0.3
    assert a.vehicle.max_step_m == 0.2
