"""pimodel.cores: the cores a computation may use, within a caller's thread budget."""

import threading

import pytest

from pimodel.cores import available_cores, thread_budget


def test_budget_bounds_the_cores_in_its_block_only():
    n = available_cores()
    with thread_budget(1):
        assert available_cores() == 1
        with thread_budget(n + 5):  # a budget never adds cores
            assert available_cores() == n
        assert available_cores() == 1
    assert available_cores() == n


def test_budget_is_the_setting_threads_own():
    seen = []
    with thread_budget(1):
        t = threading.Thread(target=lambda: seen.append(available_cores()))
        t.start()
        t.join()
    assert seen == [available_cores()]


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "2", None])
def test_bad_budget_is_refused(bad):
    with pytest.raises(ValueError, match="threads"):
        with thread_budget(bad):
            pass
