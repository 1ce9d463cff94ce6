"""The two kinds of failure a user must be told about clearly."""


class SceneError(Exception):
    """Bad input: names the file, the key and the reason. The CLI exits with status 2."""

    def __init__(self, path, key, reason):
        self.path, self.key, self.reason = str(path), key, reason
        super().__init__(f"{path}: {key}: {reason}")


class BlowUpError(Exception):
    """A numerical failure: what happened, where (particle, position) and when (time, step)."""

    def __init__(self, what, where, time, step):
        self.what, self.where, self.time, self.step = what, where, time, step
        super().__init__(f"simulation stopped at t = {time:.6g} s (step {step}): {what} ({where})")
