"""robot/software.py: the controller's software version and which dashboard commands each version knows."""
import pytest

from ur_sim_driver.errors import ConfigError
from ur_sim_driver.robot.dashboard_server import _ARGUMENT_METHODS, _SIMPLE
from ur_sim_driver.robot.software import (
    CB3_VERSION,
    COMMANDS,
    E_SERIES_VERSION,
    SoftwareVersion,
    default_version,
    parse_version,
    required,
)


def test_each_type_runs_its_series_by_default():
    assert default_version('ur5e') == E_SERIES_VERSION and E_SERIES_VERSION.e_series
    assert default_version('ur10') == CB3_VERSION and not CB3_VERSION.e_series


@pytest.mark.parametrize('text, ur_type, version', [
    ('', 'ur10e', E_SERIES_VERSION), ('5.9.1', 'ur5e', SoftwareVersion(5, 9, 1, 0)),
    ('3.14.3.1234', 'ur5', SoftwareVersion(3, 14, 3, 1234)), (' 5.21.0 ', 'ur10e', SoftwareVersion(5, 21, 0, 0))])
def test_a_version_is_parsed(text, ur_type, version):
    assert parse_version(text, ur_type) == version


@pytest.mark.parametrize('text, ur_type, words', [
    ('5.12', 'ur5e', ['not a version', 'major.minor.bugfix[.build]']),
    ('3.15.8', 'ur5e', ["'3.15.8'", 'does not run on a ur5e', '5.x']),
    ('5.12.6', 'ur10', ['does not run on a ur10', '3.x']),
    ('10.12.0', 'ur5e', ['PolyScope X', 'not simulate']),
    ('4.0.0', 'ur5e', ['does not run'])])
def test_a_bad_version_is_refused_naming_the_parameter_and_what_the_type_runs(text, ur_type, words):
    with pytest.raises(ConfigError) as info:
        parse_version(text, ur_type)
    assert "parameter 'software_version'" in str(info.value)
    assert all(w in str(info.value) for w in words), str(info.value)


def test_the_minimum_versions_separate_the_series():
    e, cb3 = E_SERIES_VERSION, CB3_VERSION
    assert required('setuserrole', e) == SoftwareVersion(5, 99, 0, 0) and required('setuserrole', cb3) is None
    assert required('set operational mode', cb3) == SoftwareVersion(3, 99, 0, 0)
    assert required('set operational mode', e) is None
    assert required('safetystatus', cb3) is not None and required('is in remote control', cb3) is not None
    assert required('get serial number', SoftwareVersion(5, 5, 0)) == SoftwareVersion(5, 6, 0, 0)
    assert required('get serial number', SoftwareVersion(5, 6, 0)) is None
    assert required('get serial number', SoftwareVersion(3, 11, 9)) == SoftwareVersion(3, 12, 0, 0)
    assert str(SoftwareVersion(5, 6, 0)) == '5.6.0-0'  # as the client library prints versions


def test_every_command_the_server_answers_has_its_minimum_versions():
    assert set(_SIMPLE) | set(_ARGUMENT_METHODS) == set(COMMANDS)
