"""The ok/FAIL lines of the python ctest scripts in this folder (test_results_md.py,
test_gpu_targets.py, test_experiment_dask.py): `check(cond, what)` prints one line a check and
keeps the failures; `summary()` prints the verdict and returns the exit code."""


class Checks:
    def __init__(self):
        self.failures = []

    def __call__(self, cond, what):
        print(("ok   " if cond else "FAIL ") + what, flush=True)
        if not cond:
            self.failures.append(what)

    def summary(self):
        print("FAILED" if self.failures else "PASSED", len(self.failures), "failure(s)")
        return 1 if self.failures else 0
