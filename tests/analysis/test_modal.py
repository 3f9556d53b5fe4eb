"""Modes and frequency response: against the paper's pencil and python-control."""

import numpy as np
import pytest

import kinetwork as kn

from .plants import paper_pencil, seed_with_motor

REST = np.zeros(4)


@pytest.fixture(scope="module")
def lin():
    return kn.linearize(seed_with_motor(), at=REST, inputs=["motor.u"],
                        outputs=["probe1.angle", "probe2.angle", "probe2.acceleration"])


def test_modes_solve_the_paper_pencil(lin):
    M, D, K = paper_pencil()
    found = kn.modes(lin)
    assert len(found) == 2 and all(m.oscillatory for m in found)
    assert found[0].frequency < found[1].frequency
    for mode in found:
        assert list(mode.shape) == ["shoulder.q", "elbow.q"]
        lam, phi = mode.eigenvalue, np.array(list(mode.shape.values()))
        # (lambda^2 M + lambda D + K) phi = 0 with the closed-form matrices
        residual = (lam ** 2 * M + lam * D + K) @ phi
        assert np.max(np.abs(residual)) < 1e-9 * np.max(np.abs(K))
        assert mode.frequency == pytest.approx(abs(lam), rel=1e-12)
        assert mode.damping == pytest.approx(-lam.real / abs(lam), rel=1e-12)
        assert max(abs(v) for v in mode.shape.values()) == pytest.approx(1.0)


def test_bode_agrees_with_python_control(lin):
    import control
    sys = lin.to_control()
    assert sys.input_labels == ["motor_u"] and sys.output_labels[0] == "probe1_angle"
    omega = np.logspace(-1, 2, 60)
    theirs = control.frequency_response(sys, omega).complex        # (outputs, inputs, omega)
    ours = lin.frequency_response(omega)
    np.testing.assert_allclose(ours, theirs, rtol=1e-10, atol=1e-14)
    for k, name in enumerate(lin.output_names):
        w, mag, phase = kn.bode(lin, "motor.u", name, omega)
        np.testing.assert_allclose(mag, np.abs(theirs[k, 0]), rtol=1e-10)
        wrapped = np.angle(np.exp(1j * np.radians(phase)))
        np.testing.assert_allclose(wrapped, np.angle(theirs[k, 0]), atol=1e-9)


def test_bode_plot_has_units_on_its_axes(lin):
    fig = kn.plot_bode(lin, outputs=["probe2.angle", "probe2.acceleration"])
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert "magnitude [dB of rad/N\u00b7m]" in labels
    assert "magnitude [dB of rad/s\u00b2/N\u00b7m]" in labels and "phase [deg]" in labels
    assert fig.axes[-1].get_xlabel() == "frequency [rad/s]"
    with pytest.raises(kn.ModelError, match="'probe9.angle' is not an output"):
        kn.plot_bode(lin, outputs=["probe9.angle"])
