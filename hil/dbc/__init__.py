"""The DBC files of the gearsim rigs, installed as the package data of
``gearsim.hil.dbc``: setup.py maps this folder to that package, so that a
wheel or an sdist carries the files themselves and an editable install reads
them here. ``gearsim.hil.shipped_dbc("gear")`` gives the installed path.
The C runner's build reads the same files (hil/CMakeLists.txt)."""
