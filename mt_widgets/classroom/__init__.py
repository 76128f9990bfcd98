"""Class progress: what students' lessons and exercises record, and what the instructor reads.

``ProgressRecorder`` writes one student's progress to the class folder the instructor sets
(``MT_WIDGETS_CLASS_FOLDER``), and nothing at all without one; ``read_class`` and
``summarise`` give the instructor's view (``mt_widgets.apps.class_view``) its data; the
``checks`` module gives exercises their checks, which explain in words what is wrong without the
expected number, against the answers of ``references``; ``roster`` reads the class list,
``names`` joins it to the pseudonyms for the instructor only, and ``baseline`` keeps a student's
novice baseline from tutorial 00.
"""

from .checks import CheckFailed, ExerciseChecks
from .progress import (
                       CLASS_FOLDER_ENV,
                       STUDENT_ENV,
                       ClassFolderError,
                       ProgressRecorder,
                       class_folder_from_env,
                       create_class_folder,
                       pseudonym,
                       read_class_meta,
                       student_name,
)
from .reader import ClassProgress, StudentProgress, read_class, read_student
from .summary import STUCK_AFTER_S, ClassSummary, StudentSummary, summarise

__all__ = ["CLASS_FOLDER_ENV", "STUCK_AFTER_S", "STUDENT_ENV", "CheckFailed", "ClassFolderError", "ClassProgress",
           "ClassSummary", "ExerciseChecks", "ProgressRecorder", "StudentProgress", "StudentSummary",
           "class_folder_from_env", "create_class_folder", "pseudonym", "read_class", "read_class_meta",
           "read_student", "student_name", "summarise"]
