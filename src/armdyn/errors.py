"""The one exception armdyn raises for invalid models and inputs."""


class ModelError(ValueError):
    """An arm model or an input that breaks a physical or structural rule.

    The message names the link (or argument) and the rule broken; armdyn never
    silently corrects a model.
    """
