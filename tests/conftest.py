import os

import hypothesis

hypothesis.settings.register_profile("obsdesign", derandomize=True, deadline=None, max_examples=60)
hypothesis.settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "obsdesign"))
