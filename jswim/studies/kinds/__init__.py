"""Every study kind, one module each: a module here that defines ``STUDY`` (a
[`jswim.studies.study.Study`][jswim.studies.study.Study]) is a study (``jswim study NAME``,
`jswim.studies.get`). docs/design.md, "Adding a study", walks through one.
"""
