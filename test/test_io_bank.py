"""The IO bank: channel counts, output and input changes, domains and spans, and every refusal."""
import math

import pytest

from ur_sim_driver.robot.io_bank import (
    CURRENT,
    N_ANALOG,
    N_DIGITAL,
    VOLTAGE,
    IoBank,
    analog_in_refusal,
    analog_out_refusal,
    digital_refusal,
    tool_voltage_refusal,
)


def test_default_bank_is_all_off_in_voltage_domains():
    bank = IoBank()
    assert len(bank.digital_in) == len(bank.digital_out) == N_DIGITAL == 18
    assert len(bank.analog_in) == len(bank.analog_out) == N_ANALOG == 2
    assert not any(bank.digital_in) and not any(bank.digital_out)
    assert bank.analog_out_domain == (VOLTAGE, VOLTAGE) and bank.tool_voltage == 0


def test_digital_output_changes_one_pin_and_leaves_the_bank_it_came_from():
    bank = IoBank()
    on = bank.with_digital_out(17, 1.0)
    assert on.digital_out[17] and not any(on.digital_out[:17])
    assert not any(bank.digital_out)  # immutable: the old snapshot is unchanged
    assert on.with_digital_out(17, 0.0).digital_out == bank.digital_out
    # As upstream casts the state to bool: any non-zero state is on.
    assert bank.with_digital_out(3, 0.5).digital_out[3]


def test_analog_output_is_a_fraction_of_the_span_read_back_in_volts_or_amperes():
    bank = IoBank().with_analog_out(0, 0.5)
    assert bank.analog_out[0] == pytest.approx(5.0)  # voltage: 0-10 V
    current = bank.with_analog_out(1, 0.5, CURRENT)
    assert current.analog_out_domain == (VOLTAGE, CURRENT)
    assert current.analog_out[1] == pytest.approx(0.012)  # 4 mA + half of 16 mA
    # set_io keeps the domain the output has.
    assert current.with_analog_out(1, 0.0).analog_out[1] == pytest.approx(0.004)
    assert current.with_analog_out(1, 0.0).analog_out_domain[1] == CURRENT


def test_inputs_standard_and_tool():
    bank = IoBank().with_digital_in(8, 1).with_analog_in(1, 7.5).with_analog_in(3, 0.01, CURRENT)
    assert bank.digital_in[8] and sum(bank.digital_in) == 1
    assert bank.analog_in == (0.0, 7.5)
    assert bank.tool_analog_in == (0.0, 0.01) and bank.tool_analog_in_range == (VOLTAGE, CURRENT)
    assert bank.tool_voltage == 0
    assert IoBank().with_tool_voltage(24.0).tool_voltage == 24


@pytest.mark.parametrize('pin, state, words', [
    (18, 1.0, ['pin = 18', '0..17']),
    (-1, 1.0, ['pin = -1', '0..17']),
    (0, math.nan, ['state = nan', 'finite']),
])
def test_digital_refusals_name_field_value_and_limit(pin, state, words):
    reason = digital_refusal(pin, state)
    assert reason is not None and all(w in reason for w in words), reason
    assert digital_refusal(17, 1.0) is None and digital_refusal(0, 0.0) is None


@pytest.mark.parametrize('pin, value, domain, words', [
    (2, 0.5, None, ['pin = 2', '0..1']),
    (0, 1.5, None, ['state = 1.5', '[0, 1]']),
    (0, -0.1, None, ['state = -0.1', '[0, 1]']),
    (1, 0.5, 7, ['domain = 7', 'CURRENT', 'VOLTAGE']),
])
def test_analog_output_refusals(pin, value, domain, words):
    reason = analog_out_refusal(pin, value, domain)
    assert reason is not None and all(w in reason for w in words), reason
    assert analog_out_refusal(1, 1.0, CURRENT) is None and analog_out_refusal(0, 0.0) is None


def test_analog_input_refusals_follow_the_domain_span():
    bank = IoBank()
    assert analog_in_refusal(bank, 0, 10.0) is None
    reason = analog_in_refusal(bank, 0, 10.5)
    assert reason is not None and '10.5 V' in reason and '[0.0, 10.0] V' in reason
    # 12 mA is fine in the current domain; 25 mA and 2 mA are not.
    assert analog_in_refusal(bank, 2, 0.012, CURRENT) is None
    assert '[0.004, 0.02] A' in analog_in_refusal(bank, 2, 0.025, CURRENT)
    assert analog_in_refusal(bank.with_analog_in(1, 0.012, CURRENT), 1, 0.002) is not None
    assert 'pin = 4' in analog_in_refusal(bank, 4, 1.0)


def test_tool_voltage_is_0_12_or_24():
    for v in (0, 12.0, 24):
        assert tool_voltage_refusal(v) is None
    for v in (5.0, 48.0, math.nan):
        reason = tool_voltage_refusal(v)
        assert reason is not None and f'{v}' in reason and '0, 12, 24' in reason
