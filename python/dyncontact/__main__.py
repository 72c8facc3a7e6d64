"""The dyncontact command line from Python: ``python -m dyncontact ARGS`` (and the ``dyncontact``
console script) run the CLI's own code with ARGS — ``run``, ``check``, ``sweep`` (with ``sweep
point`` and ``sweep collect``), ``refine``, ``study penalty`` — and exit with its code. A sweep's
Snakefile written by :func:`dyncontact.sweep` runs its points this way."""
import signal
import sys

from dyncontact._dyncontact import cli_main


def main() -> int:
    # the CLI handles SIGINT itself (a run stops after its step, writes a checkpoint and exits
    # 130); Python's handler would raise KeyboardInterrupt once it returns
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    return cli_main(["dyncontact", *sys.argv[1:]])


if __name__ == "__main__":
    sys.exit(main())
