"""Two load levels closer than the stepper resolves are refused at ``steps[i]``."""
import pytest

from helpers import CONFIGS, load_raw


def test_levels_closer_than_the_stepper_resolves_are_refused():
    """steps [10, 20, 30, 30.0000000000001, 40] on the psi 45 column passed the config ('increase
    strictly') and ended in a traceback, exit 1 (UnboundLocalError: 'reason', stepper._reach: the
    stepper, at 30 within 1e-14, ran no sub-step for the fourth level); now one line at steps[3]."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.config.values import ConfigError
    raw = load_raw("uniaxial_neohookean.yaml")
    with pytest.raises(ConfigError) as info:
        parse_config(dict(raw, steps=[0.1, 0.3, 0.3 + 3e-15, 1.0]), base_dir=CONFIGS)
    assert info.value.path == "steps[2]" and "must exceed steps[1] = 0.3 by more than 1e-12" in str(info.value)
    parse_config(dict(raw, steps=[0.1, 0.3, 0.3 * (1 + 1e-11), 1.0]), base_dir=CONFIGS)
