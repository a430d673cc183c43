"""What umbmark writes besides the formats of :mod:`umbmark.sources` (whose writers sit
beside their readers): the output-file plan checked before any file is written
(:mod:`~umbmark.outputs.files`), TUM trajectories, figures and the HTML report; always
whole or not at all (:mod:`umbmark.core.atomic`). The map: ``docs/architecture.md``."""
