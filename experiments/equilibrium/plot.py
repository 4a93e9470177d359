"""summary.md of an equilibrium study folder (the tables; no picture): experiments/equilibrium/plot.py DIR."""
import os
import subprocess
import sys

here = os.path.dirname(os.path.abspath(__file__))
sys.exit(subprocess.call([sys.executable, os.path.join(here, "summary.py")] + sys.argv[1:2]))
