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
    polyscope_x_minimum,
    required,
)


def test_each_type_runs_its_series_by_default():
    assert default_version('ur5e') == E_SERIES_VERSION and E_SERIES_VERSION.e_series
    assert default_version('ur10') == CB3_VERSION and not CB3_VERSION.e_series


@pytest.mark.parametrize('text, ur_type, version', [
    ('', 'ur10e', E_SERIES_VERSION), ('5.9.1', 'ur5e', SoftwareVersion(5, 9, 1, 0)),
    ('3.14.3.1234', 'ur5', SoftwareVersion(3, 14, 3, 1234)), (' 5.21.0 ', 'ur10e', SoftwareVersion(5, 21, 0, 0)),
    ('10.12.0', 'ur15', SoftwareVersion(10, 12, 0, 0)), ('10.11.0', 'ur18', SoftwareVersion(10, 11, 0, 0))])
def test_a_version_is_parsed(text, ur_type, version):
    assert parse_version(text, ur_type) == version


@pytest.mark.parametrize('text, ur_type, words', [
    ('5.12', 'ur5e', ['not a version', 'major.minor.bugfix[.build]']),
    ('3.15.8', 'ur5e', ["'3.15.8'", 'does not run on a ur5e', '5.x']),
    ('5.12.6', 'ur10', ['does not run on a ur10', '3.x']),
    ('10.12.0', 'ur10', ['does not run on a ur10', '3.x (CB3 software)']),
    ('10.10.0', 'ur8long', ['does not run on a ur8long', '10.x (PolyScope X) from 10.11.0']),
    ('11.0.0', 'ur30', ['5.x (PolyScope 5) from 5.15.0 or 10.x (PolyScope X) from 10.7.0']),
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


@pytest.mark.parametrize('ur_type, first', [
    ('ur3e', '10.7.0'), ('ur5e', '10.7.0'), ('ur10e', '10.7.0'), ('ur16e', '10.7.0'), ('ur20', '10.7.0'),
    ('ur30', '10.7.0'), ('ur15', '10.8.0'), ('ur7e', '10.9.0'), ('ur12e', '10.9.0'), ('ur8long', '10.11.0'),
    ('ur18', '10.11.0'), ('ur3', None), ('ur5', None), ('ur10', None)])
def test_polyscope_x_runs_on_the_e_series_and_ur_series_from_the_types_first_release(ur_type, first):
    x = polyscope_x_minimum(ur_type)
    assert (x and x.dotted()[:-2]) == first
    if first is not None:
        assert parse_version(first, ur_type).polyscope_x and not parse_version('', ur_type).polyscope_x
