"""Parameters of the ur_glue_studio executable."""
import pytest

from ur_glue_planner.studio.node import DEFAULTS, parse_params


def test_defaults_and_overrides():
    assert parse_params({}) == DEFAULTS
    got = parse_params({'job': 'config/glue_job.yaml', 'port': 9000, 'use_sim_time': False})
    assert got['job'] == 'config/glue_job.yaml' and got['port'] == 9000 and got['host'] == '127.0.0.1'


@pytest.mark.parametrize('raw, message', [
    ({'prot': 1}, "parameter 'prot' is unknown; known: job, host, port"),
    ({'port': 0}, r'port: 0 is not an integer in \[1, 65535\]'),
    ({'port': '80'}, r"port: '80' is not an integer"),
    ({'host': 5}, 'host: 5 is not a string'),
])
def test_bad_parameters_are_named(raw, message):
    with pytest.raises(ValueError, match=message):
        parse_params(raw)
