"""The fuzzers (inputs.py: file contents in-process; processes.py: interrupted and misdirected choreo
processes) and their short deterministic runs (test_inputs.py, test_processes.py). The long runs:
``python -m tests.fuzz.inputs --help`` and ``python -m tests.fuzz.processes --help`` from the repository root."""
