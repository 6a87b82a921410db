"""pytest collects the Markdown pages of docs/ as doctests (``--doctest-glob=*.md``); the site's
build files are not tests: Sphinx's configuration, its local extensions, the gallery's scripts
(run by ``make docs``, which fails when their assertions do) and what the build generates."""

collect_ignore = ["conf.py", "conftest.py"]  # this file too: tests/conftest.py is the module "conftest"
collect_ignore_glob = ["_ext/*", "examples/*", "gallery/*", "api/*", "_build/*", "notebooks/*"]
