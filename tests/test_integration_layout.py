"""The layout built from blocks owns every index."""

import numpy as np
import pytest

from inskit.errors import InputError
from inskit.integration import (GyroBias, PositionError, SensorNoise, StateBlock, StateLayout, TimeOffset,
                                ins_blocks)

NOISE = SensorNoise(2e-3, 3e-2, 1e-5, 1e-4, 300.0)


def test_slices_and_aux_follow_the_block_order():
    lay = StateLayout(ins_blocks(NOISE, scale_factors=True, lever_arm=True, time_offset=True))
    assert lay.size == 25 and lay.aux_size == 16
    assert [lay.slice(n) for n in ("pos", "vel", "att")] == [slice(0, 3), slice(3, 6), slice(6, 9)]
    assert lay.slice("time_offset") == slice(24, 25) and lay.aux_slice("time_offset") == slice(15, 16)
    assert lay.slice("odometer") is None and "odometer" not in lay
    assert np.array_equal(lay.aux_state_index, np.arange(9, 25))
    assert lay.kernel_index().tolist() == [9, 12, 15, 18, 0, 3, 6, 9, 25]
    assert len(lay.state_names()) == lay.size == len(lay.sigma_names())
    assert len(lay.estimate_names()) == lay.aux_size


def test_noise_and_initial_covariance_come_from_the_blocks():
    lay = StateLayout(ins_blocks(NOISE))
    q = lay.process_noise()
    assert np.allclose(q[3:6], 3e-2**2) and np.allclose(q[6:9], 2e-3**2)
    assert np.allclose(q[9:12], 2 * 1e-5**2 / 300.0)  # Gauss-Markov PSD
    assert np.allclose(q[0:3], 0.0)
    P0 = lay.initial_covariance()
    assert np.array_equal(P0, np.diag(np.diag(P0)))
    assert P0[8, 8] == pytest.approx(np.radians(5.0) ** 2)


def test_initial_estimates_go_to_aux():
    lay = StateLayout(ins_blocks(gyro_bias0=(1e-3, 2e-3, 3e-3), time_offset=True, time_offset0=-0.25))
    aux = lay.initial_aux()
    assert aux[lay.aux_slice("bg")].tolist() == [1e-3, 2e-3, 3e-3]
    assert aux[lay.aux_slice("time_offset")].tolist() == [-0.25]


def test_pattern_grows_with_the_blocks_only():
    base = StateLayout(ins_blocks())
    extra = StateLayout(ins_blocks() + [StateBlock("k", ("a", "b"), "", 1.0, entries=((0, "k", 1, 2.0),))])
    nb, ne = len(base.transition_pattern()[0]), len(extra.transition_pattern()[0])
    assert ne == nb + 1  # the one constant entry


@pytest.mark.parametrize("blocks,match", [
    (lambda: ins_blocks()[1:], "starts with the navigation blocks"),
    (lambda: ins_blocks() + [TimeOffset(), TimeOffset()], "unique"),
    (lambda: ins_blocks() + [GyroBias()], "unique"),
    (lambda: ins_blocks() + [PositionError()], "unique"),
    (lambda: ins_blocks() + [StateBlock("k", ("a",), "", entries=((0, "nope", 0, 1.0),))], "not in the layout"),
    (lambda: ins_blocks() + [StateBlock("k", ("a",), "", entries=((0, "k", 3, 1.0),))], "out of range"),
    (lambda: ins_blocks() + ["bg"], "StateBlock"),
])
def test_bad_layouts_are_refused(blocks, match):
    with pytest.raises(InputError, match=match):
        StateLayout(blocks())


def test_columns_are_named_only_on_request():
    lay = StateLayout(ins_blocks(time_offset=True))
    aux = np.tile(lay.initial_aux(), (4, 1))
    sig = np.ones((4, lay.size))
    cols = lay.columns(aux, sig, sigma_blocks=("pos",))
    assert {"sigma_n_m", "sigma_e_m", "sigma_d_m", "bg_x_rad_s", "time_offset_s"} <= set(cols)
    assert "sigma_vn_m_s" not in cols
    assert "sigma_bg_x_rad_s" in lay.columns(aux, sig)
