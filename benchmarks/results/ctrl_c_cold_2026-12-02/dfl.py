"""exec the command given with SIGINT at its default disposition and unblocked."""

import os
import signal
import sys

signal.signal(signal.SIGINT, signal.SIG_DFL)
signal.pthread_sigmask(signal.SIG_UNBLOCK, [signal.SIGINT])
os.execvp(sys.argv[1], sys.argv[1:])
