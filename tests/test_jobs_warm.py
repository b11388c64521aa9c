"""inskit.jobs.warm: numba's set-up started once, in a daemon thread, and done by the time it is joined."""

import subprocess
import sys


def test_the_warm_up_runs_once_in_a_daemon_thread_and_loads_numba():
    code = ("import sys, threading\n"
            "from inskit.jobs import warm\n"
            "warm.warm_compiled_code(); t = warm._WARMING\n"
            "warm.warm_compiled_code(); assert warm._WARMING is t  # once per process\n"
            "assert t.daemon and t.name == 'inskit-warm'\n"
            "t.join(120)\n"
            "assert not t.is_alive()\n"
            "from inskit.rotations import _rotvec_quat_rows\n"
            "assert _rotvec_quat_rows.signatures  # the cached kernel is loaded: numba is set up\n"
            "print('ok')\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr
