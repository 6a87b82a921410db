import os

import hypothesis

hypothesis.settings.register_profile("obsdesign", derandomize=True, deadline=None, max_examples=60)
hypothesis.settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "obsdesign"))


OCTAVE_FILES = ("test_controller_export.py", "test_compensation_modes.py")
#: Documentation pages whose examples run a design search end to end (docs/tune.md: 7 s).
SLOW_PAGES = ("tune.md",)


def pytest_collection_modifyitems(config, items):
    """The controller-export cases that run GNU Octave (one interpreter start each, 2-20 s on the
    2-core machine; the compensation modes' reference exports 7-9 s each) are slow: ``make test`` runs
    them, ``make test-fast`` skips them. The C, Python and JavaScript cases of the same tests stay in
    the fast run. So are the examples of :data:`SLOW_PAGES`."""
    import pytest

    for item in items:
        if (item.path.name in OCTAVE_FILES and "octave" in item.name
                and not item.name.startswith("test_controller_files_errors")):
            item.add_marker(pytest.mark.slow)
        if item.path.name in SLOW_PAGES and item.path.parent.name == "docs":
            item.add_marker(pytest.mark.slow)


# The on-disk memo (obsdesign._memo) of this test session: its own empty folder, never the user's
# ~/.cache, so every session computes each kept result once and then reads it back.
import atexit  # noqa: E402
import shutil  # noqa: E402
import tempfile  # noqa: E402

os.environ["OBSDESIGN_CACHE_DIR"] = tempfile.mkdtemp(prefix="obsdesign-test-memo-")
atexit.register(shutil.rmtree, os.environ["OBSDESIGN_CACHE_DIR"], ignore_errors=True)
