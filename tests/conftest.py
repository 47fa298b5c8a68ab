import dask
import pytest


def _refuse(*args, **kwargs):
    raise RuntimeError("dask computed before it was asked to")


@pytest.fixture
def no_compute():
    """Inside this fixture any dask computation raises."""
    with dask.config.set(scheduler=_refuse):
        yield
