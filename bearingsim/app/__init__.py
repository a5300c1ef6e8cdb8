"""What the user runs (edge, on top of everything else):

``workflows`` the case-driven workflows the command line, notebooks, README and tests share
``sets``      bearing sets on the edge: their workflows, text, files and figures
``cli``       the ``bearingsim`` command: argparse, printing and exit codes only
"""
