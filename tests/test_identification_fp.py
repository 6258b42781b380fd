"""detect / identify / identify_windows / ResidualWindows refuse a functionally pooled model (FPResults) itself,
naming the argument and pointing to its point model ``.at(k)`` (before: a raw ``residuals() missing 'k'`` or
``no attribute 'lags'``)."""

from __future__ import annotations

import numpy as np
import pytest

import tsfdi
from tsfdi.models import FPAR
from tsfdi.windows import ResidualWindows


@pytest.fixture(scope="module")
def fp():
    rng = np.random.default_rng(0)
    ks = [0.0, 0.5, 1.0]
    return FPAR([rng.standard_normal(300) for _ in ks], ks, 2, degree=1).fit()


def test_fp_results_are_refused_naming_the_argument_and_at_k(fp):
    y = np.random.default_rng(1).standard_normal(400)
    hint = r"is a functionally pooled model \(FPResults\): give its point model .*\.at\(k\)"
    with pytest.raises(TypeError, match="^baseline " + hint):
        tsfdi.detect(y, fp, tsfdi.FTest())
    with pytest.raises(TypeError, match=r"^models\['fault'\] " + hint):
        tsfdi.identify(y, {"healthy": fp.at(0.5), "fault": fp})
    with pytest.raises(TypeError, match=r"^models\['healthy'\] " + hint):
        tsfdi.identify_windows(y, {"healthy": fp}, window=100, step=100)
    with pytest.raises(TypeError, match=r"^models\['healthy'\] " + hint):
        ResidualWindows({"healthy": fp})
    # the point model at k is taken
    assert tsfdi.identify_windows(y, {"healthy": fp.at(0.5)}, window=100, step=100).labels is not None
