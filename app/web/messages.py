"""The message catalogue: key -> {"en": ..., "zh-CN": ...}.  Tests check both exist."""

MESSAGES: dict[str, dict[str, str]] = {
    # application frame
    "app.name": {"en": "GyroLab", "zh-CN": "GyroLab"},
    "app.tagline": {"en": "FOG north-finding lab", "zh-CN": "光纤陀螺寻北实验"},
    "app.footer": {
        "en": "Four-position north finding, latitude and Earth rate",
        "zh-CN": "四位置法寻北、纬度与地球自转角速度测量",
    },
    "nav.label": {"en": "Main navigation", "zh-CN": "主导航"},
    "nav.dashboard": {"en": "Dashboard", "zh-CN": "主页"},
    "nav.password": {"en": "Password", "zh-CN": "修改密码"},
    "nav.logout": {"en": "Log out", "zh-CN": "退出登录"},
    "role.teacher": {"en": "teacher", "zh-CN": "教师"},
    "role.student": {"en": "student", "zh-CN": "学生"},
    "role.admin": {"en": "administrator", "zh-CN": "管理员"},
    "common.optional": {"en": "optional", "zh-CN": "可选"},
    # errors
    "error.title": {"en": "Something is not right", "zh-CN": "出了点问题"},
    "error.back": {"en": "Back to the dashboard", "zh-CN": "返回主页"},
    "error.forbidden": {
        "en": "You do not have access to this page.",
        "zh-CN": "您无权访问此页面。",
    },
    "error.csrf": {
        "en": "This form has expired or did not come from GyroLab. "
        "Go back, reload the page and try again.",
        "zh-CN": "此表单已过期或并非来自 GyroLab。请返回、刷新页面后重试。",
    },
    "error.not_found": {
        "en": "This page does not exist, or you cannot see it.",
        "zh-CN": "页面不存在，或您无权查看。",
    },
    "error.method": {
        "en": "This address does not accept that kind of request.",
        "zh-CN": "此地址不接受这种请求。",
    },
    "error.too_large": {"en": "The upload is too large.", "zh-CN": "上传的内容太大。"},
    "error.busy": {
        "en": "The lab is very busy this moment, so nothing was saved. Try again in a few seconds.",
        "zh-CN": "系统此刻非常繁忙，本次内容未保存。请几秒钟后再试。",
    },
    "error.storage": {
        "en": "The database cannot be written just now (read-only or full storage), so "
        "nothing was saved. Try again in a minute; if it persists, tell the administrator.",
        "zh-CN": "数据库暂时无法写入（只读或存储空间已满），本次内容未保存。请稍后再试；"
        "如果持续出现，请联系管理员。",
    },
    "error.nul_text": {
        "en": "Text may not contain NUL (\\0) characters; nothing was saved.",
        "zh-CN": "文本中不能含有 NUL（\\0）字符；未保存任何内容。",
    },
    "error.bad_request": {
        "en": "The form was incomplete or had invalid values.",
        "zh-CN": "表单不完整或包含无效的值。",
    },
    "error.generic": {"en": "The request could not be completed.", "zh-CN": "请求无法完成。"},
    # login
    "login.title": {"en": "Log in", "zh-CN": "登录"},
    "login.intro": {
        "en": "Students and teachers log in with the account their school gave them.",
        "zh-CN": "学生和教师请使用学校分配的账号登录。",
    },
    "login.username": {"en": "Username or student number", "zh-CN": "用户名或学号"},
    "login.password": {"en": "Password", "zh-CN": "密码"},
    "login.submit": {"en": "Log in", "zh-CN": "登录"},
    "login.failed": {"en": "Wrong username or password.", "zh-CN": "用户名或密码错误。"},
    "login.throttled": {
        "en": "Too many failed log-in attempts. Wait {minutes} minutes and "
        "try again, or ask your teacher to reset your password.",
        "zh-CN": "登录失败次数过多。请等待 {minutes} 分钟后再试，或请老师重置密码。",
    },
    "login.slow_down": {
        "en": "Wrong passwords slow down log-in: wait {seconds} seconds and try again.",
        "zh-CN": "密码错误次数较多，登录已放慢：请等待 {seconds} 秒后再试。",
    },
    "login.busy": {
        "en": "The server is busy checking passwords. Try again in a moment.",
        "zh-CN": "服务器正忙于验证密码，请稍后再试。",
    },
    "login.logged_out": {"en": "You have logged out.", "zh-CN": "您已退出登录。"},
    # password
    "password.title": {"en": "Change password", "zh-CN": "修改密码"},
    "password.forced": {
        "en": "You are using an initial password. Choose your own password before you continue.",
        "zh-CN": "您正在使用初始密码。请先设置自己的密码再继续。",
    },
    "password.current": {"en": "Current password", "zh-CN": "当前密码"},
    "password.new": {"en": "New password", "zh-CN": "新密码"},
    "password.confirm": {"en": "New password again", "zh-CN": "再次输入新密码"},
    "password.rule": {
        "en": "At least {minimum} characters, not your username.",
        "zh-CN": "至少 {minimum} 个字符，且不能与用户名相同。",
    },
    "password.submit": {"en": "Save new password", "zh-CN": "保存新密码"},
    "password.wrong_current": {"en": "The current password is wrong.", "zh-CN": "当前密码不正确。"},
    "password.mismatch": {
        "en": "The two new passwords differ.",
        "zh-CN": "两次输入的新密码不一致。",
    },
    "password.unchanged": {
        "en": "The new password must differ from the current one.",
        "zh-CN": "新密码必须与当前密码不同。",
    },
    "password.too_short": {
        "en": "The new password needs at least {minimum} characters.",
        "zh-CN": "新密码至少需要 {minimum} 个字符。",
    },
    "password.too_long": {"en": "The new password is too long.", "zh-CN": "新密码太长。"},
    "password.same_as_username": {
        "en": "The new password must not be your username.",
        "zh-CN": "新密码不能与用户名相同。",
    },
    "password.changed": {
        "en": "Your password has been changed. Other sessions were logged out.",
        "zh-CN": "密码已修改，其他设备上的登录已失效。",
    },
    # dashboards
    "dashboard.teacher_title": {"en": "Welcome, {name}", "zh-CN": "欢迎，{name}"},
    "dashboard.student_title": {"en": "Welcome, {name}", "zh-CN": "欢迎，{name}"},
    "dashboard.my_courses": {"en": "My courses", "zh-CN": "我的课程"},
    "dashboard.no_courses": {
        "en": "You are not enrolled in any course yet. Enter the course code your teacher "
        "gives you, or open their join link.",
        "zh-CN": "您还没有加入任何课程。请输入老师给您的课程代码，或打开老师发的加入链接。",
    },
    # courses
    "course.list_title": {"en": "My courses", "zh-CN": "我的课程"},
    "course.name": {"en": "Course name", "zh-CN": "课程名称"},
    "course.name_placeholder": {
        "en": "e.g. Inertial navigation lab, class 1",
        "zh-CN": "例如：惯性导航实验 1 班",
    },
    "course.students": {"en": "Students", "zh-CN": "学生数"},
    "course.status": {"en": "Status", "zh-CN": "状态"},
    "course.teacher": {"en": "Teacher", "zh-CN": "教师"},
    "course.none_yet": {
        "en": "No courses yet. Create your first one.",
        "zh-CN": "还没有课程，请创建第一门课程。",
    },
    "course.create_title": {"en": "New course", "zh-CN": "新建课程"},
    "course.create": {"en": "Create course", "zh-CN": "创建课程"},
    "course.created": {"en": "Course “{name}” created.", "zh-CN": "课程“{name}”已创建。"},
    "course.name_required": {"en": "Give the course a name.", "zh-CN": "请填写课程名称。"},
    "course.renamed": {"en": "Course renamed to “{name}”.", "zh-CN": "课程已改名为“{name}”。"},
    "course.archived": {
        "en": "Course archived. Students no longer see it.",
        "zh-CN": "课程已归档，学生将不再看到它。",
    },
    "course.unarchived": {"en": "Course restored.", "zh-CN": "课程已恢复。"},
    "course.archived_badge": {"en": "archived", "zh-CN": "已归档"},
    "course.active_badge": {"en": "active", "zh-CN": "进行中"},
    "course.settings": {"en": "Course settings", "zh-CN": "课程设置"},
    "course.rename": {"en": "Rename", "zh-CN": "改名"},
    "course.archive": {"en": "Archive course", "zh-CN": "归档课程"},
    "course.unarchive": {"en": "Restore course", "zh-CN": "恢复课程"},
    # roster
    "roster.title": {"en": "Students", "zh-CN": "学生名单"},
    "roster.username": {"en": "Username / student number", "zh-CN": "用户名/学号"},
    "roster.display_name": {"en": "Name", "zh-CN": "姓名"},
    "roster.email": {"en": "Email", "zh-CN": "邮箱"},
    "roster.actions": {"en": "Actions", "zh-CN": "操作"},
    "roster.empty": {
        "en": "No students yet. Import a roster or add them one by one.",
        "zh-CN": "还没有学生。请导入名单或逐个添加。",
    },
    "roster.initial_password": {"en": "initial password", "zh-CN": "初始密码"},
    "roster.initial_password_hint": {
        "en": "Has not chosen a password yet",
        "zh-CN": "尚未设置自己的密码",
    },
    "roster.reset": {"en": "Reset password", "zh-CN": "重置密码"},
    "roster.reset_confirm": {
        "en": "Give {username} a new one-time password?",
        "zh-CN": "为 {username} 生成新的一次性密码？",
    },
    "roster.remove": {"en": "Remove", "zh-CN": "移出课程"},
    "roster.remove_confirm": {
        "en": "Remove {username} from this course? Their account and work are kept.",
        "zh-CN": "将 {username} 移出本课程？其账号和实验数据会保留。",
    },
    "roster.removed": {
        "en": "{username} was removed from the course; their work is kept.",
        "zh-CN": "{username} 已移出课程，其实验数据仍保留。",
    },
    "roster.import_title": {"en": "Import a roster (CSV)", "zh-CN": "导入学生名单（CSV）"},
    "roster.import_help": {
        "en": "Columns: username or student number, name, optional email. "
        "UTF-8 or Excel's Chinese CSV; a header row is optional. "
        "Nothing is created if any row has a problem.",
        "zh-CN": "列：用户名或学号、姓名、邮箱（可选）。支持 UTF-8 或 Excel "
        "导出的中文 CSV，表头可有可无。只要有一行有问题，就不会创建任何账号。",
    },
    "roster.file": {"en": "Roster file", "zh-CN": "名单文件"},
    "roster.import": {"en": "Import", "zh-CN": "导入"},
    "roster.import_failed": {
        "en": "The roster was not imported; fix these rows and try again:",
        "zh-CN": "名单未导入，请修改以下各行后重试：",
    },
    "roster.line": {"en": "Line {line}", "zh-CN": "第 {line} 行"},
    "roster.too_large": {
        "en": "The file is larger than {limit_kb} kB.",
        "zh-CN": "文件超过 {limit_kb} kB。",
    },
    "roster.too_many": {
        "en": "More than {limit} students in one file.",
        "zh-CN": "单个文件的学生超过 {limit} 人。",
    },
    "roster.encoding": {
        "en": "The file is neither UTF-8 nor GB18030 text. Save it as CSV (UTF-8).",
        "zh-CN": "文件既不是 UTF-8 也不是 GB18030 文本，请另存为 CSV（UTF-8）。",
    },
    "roster.empty_file": {"en": "The file is empty.", "zh-CN": "文件是空的。"},
    "roster.no_name_column": {
        "en": "The header has no name column (name / 姓名).",
        "zh-CN": "表头中没有姓名列（name / 姓名）。",
    },
    "roster.bad_username": {
        "en": "“{value}” is not a valid username: use 1–64 letters, digits, "
        "dot, dash or underscore.",
        "zh-CN": "“{value}”不是有效的用户名：请使用 1–64 个字母、数字、点、连字符或下划线。",
    },
    "roster.no_name": {"en": "“{value}” has no name.", "zh-CN": "“{value}”缺少姓名。"},
    "roster.name_too_long": {
        "en": "The name of “{value}” is longer than 128 characters.",
        "zh-CN": "“{value}”的姓名超过 128 个字符。",
    },
    "roster.bad_email": {
        "en": "“{value}” is not an email address.",
        "zh-CN": "“{value}”不是有效的邮箱地址。",
    },
    "roster.duplicate": {
        "en": "“{value}” already appears on line {other}.",
        "zh-CN": "“{value}”已在第 {other} 行出现。",
    },
    "roster.not_student": {
        "en": "“{value}” belongs to a teacher account.",
        "zh-CN": "“{value}”是教师账号。",
    },
    "roster.add_title": {"en": "Add one student", "zh-CN": "添加单个学生"},
    "roster.add": {"en": "Add student", "zh-CN": "添加学生"},
    "roster.enrolled_existing": {
        "en": "{username} already had an account and is now enrolled.",
        "zh-CN": "{username} 已有账号，现已加入本课程。",
    },
    "account.exists": {
        "en": "The username “{username}” is taken.",
        "zh-CN": "用户名“{username}”已被占用。",
    },
    "account.not_student": {
        "en": "“{username}” is a teacher account, not a student.",
        "zh-CN": "“{username}”是教师账号，不是学生账号。",
    },
    # one-time credentials
    "credentials.title": {"en": "New student accounts", "zh-CN": "新建的学生账号"},
    "credentials.reset_title": {"en": "New one-time password", "zh-CN": "新的一次性密码"},
    "credentials.once": {
        "en": "These initial passwords are shown only now. Download or copy "
        "them; each student must choose a new password at first log-in.",
        "zh-CN": "这些初始密码只显示这一次，请下载或复制。学生首次登录时必须设置新密码。",
    },
    "credentials.password": {"en": "Initial password", "zh-CN": "初始密码"},
    "credentials.download": {"en": "Download as CSV", "zh-CN": "下载 CSV"},
    "credentials.enrolled_title": {
        "en": "Existing accounts enrolled",
        "zh-CN": "已有账号已加入课程",
    },
    "credentials.back": {"en": "Back to the course", "zh-CN": "返回课程"},
    "credentials.back_admin": {"en": "Back to the accounts", "zh-CN": "返回账号列表"},
    "credentials.needs_code_title": {
        "en": "Existing accounts not enrolled",
        "zh-CN": "已有账号，尚未加入课程",
    },
    "credentials.needs_code_help": {
        "en": "These students already have an account that another teacher or an "
        "administrator created. They join themselves with the course code {code} (or your "
        "join link); you cannot add them or reset their passwords.",
        "zh-CN": "这些学生已有其他老师或管理员创建的账号，需要自己用课程代码 {code}（或加入链接）"
        "加入课程；您不能直接添加他们，也不能重置他们的密码。",
    },
    "roster.needs_consent": {
        "en": "“{username}” already has an account that you did not create. The student "
        "joins this course with the code {code} (or your join link).",
        "zh-CN": "“{username}”已有账号，但不是您创建的。请学生用课程代码 {code}（或加入链接）"
        "自己加入本课程。",
    },
    "roster.reset_needs_admin": {
        "en": "You may reset only the passwords of accounts your roster created and that no "
        "other teacher's course holds. Ask an administrator to reset {username}'s password.",
        "zh-CN": "您只能重置由您的名单创建、且不在其他老师课程中的账号的密码。"
        "请联系管理员重置 {username} 的密码。",
    },
    "roster.reset_by_admin": {"en": "reset: administrator", "zh-CN": "重置：找管理员"},
    "roster.reset_by_admin_hint": {
        "en": "This account was not created by your roster, or another teacher's course "
        "holds it: only an administrator may reset its password.",
        "zh-CN": "此账号不是您的名单创建的，或也在其他老师的课程中：只有管理员可以重置其密码。",
    },
    # joining a course
    "join.title": {"en": "Join a course", "zh-CN": "加入课程"},
    "join.help": {
        "en": "Your teacher gives you an 8-character course code or a join link.",
        "zh-CN": "老师会给您一个 8 位课程代码或一个加入链接。",
    },
    "join.code": {"en": "Course code", "zh-CN": "课程代码"},
    "join.submit": {"en": "Join", "zh-CN": "加入"},
    "join.confirm": {
        "en": "Join the course “{name}”?",
        "zh-CN": "加入课程“{name}”？",
    },
    "join.joined": {"en": "You joined “{name}”.", "zh-CN": "您已加入“{name}”。"},
    "join.bad_code": {
        "en": "No open course has this code. Check it with your teacher.",
        "zh-CN": "没有使用此代码的开放课程，请向老师核对。",
    },
    "join.students_only": {
        "en": "Only student accounts join courses.",
        "zh-CN": "只有学生账号可以加入课程。",
    },
    "join.card_title": {"en": "Students join with", "zh-CN": "学生加入方式"},
    "join.card_help": {
        "en": "Students who already have an account join with this code or link. Students "
        "your roster creates are enrolled at once.",
        "zh-CN": "已有账号的学生用此代码或链接加入；由您的名单新建的学生会直接加入。",
    },
    "join.link": {"en": "Join link", "zh-CN": "加入链接"},
    "join.rotate": {"en": "New code", "zh-CN": "更换代码"},
    "join.rotate_confirm": {
        "en": "Make a new code? The old code and link stop working.",
        "zh-CN": "更换代码？旧代码和旧链接将失效。",
    },
    "join.code_rotated": {
        "en": "The new course code is {code}.",
        "zh-CN": "新的课程代码是 {code}。",
    },
    # administrators
    "nav.admin": {"en": "Accounts", "zh-CN": "账号管理"},
    "admin.title": {"en": "Accounts", "zh-CN": "账号管理"},
    "admin.accounts": {"en": "All accounts", "zh-CN": "全部账号"},
    "admin.search": {"en": "Username or name", "zh-CN": "用户名或姓名"},
    "admin.search_button": {"en": "Search", "zh-CN": "搜索"},
    "admin.role": {"en": "Role", "zh-CN": "角色"},
    "admin.created_by": {"en": "Created by", "zh-CN": "创建者"},
    "admin.courses": {"en": "Courses", "zh-CN": "课程数"},
    "admin.first_n": {
        "en": "Only the first {n} accounts are shown: search to narrow the list.",
        "zh-CN": "只显示前 {n} 个账号，请搜索以缩小范围。",
    },
    "admin.create_title": {"en": "New account", "zh-CN": "新建账号"},
    "admin.create": {"en": "Create with a one-time password", "zh-CN": "创建（一次性密码）"},
    "admin.created_title": {"en": "New account", "zh-CN": "新账号"},
    "admin.bad_role": {"en": "Choose a role.", "zh-CN": "请选择角色。"},
    "admin.prune_title": {"en": "Old re-recordings", "zh-CN": "旧的重复记录"},
    "admin.prune_help": {
        "en": "Remove recordings that were replaced by a newer take long ago and that no "
        "submission refers to. Submitted data is never removed.",
        "zh-CN": "删除早已被新记录取代、且未被任何提交引用的记录。已提交的数据永远不会被删除。",
    },
    "admin.prune_days": {"en": "Replaced more than (days) ago", "zh-CN": "被取代超过（天）"},
    "admin.prune": {"en": "Remove", "zh-CN": "删除"},
    "admin.prune_confirm": {
        "en": "Remove these old recordings for good?",
        "zh-CN": "确定永久删除这些旧记录？",
    },
    "admin.pruned": {
        "en": "Removed {n} old recording(s) replaced more than {days} days ago ({mb} MB).",
        "zh-CN": "已删除 {n} 条被取代超过 {days} 天的旧记录（{mb} MB）。",
    },
    "admin.reset_refused": {
        "en": "Administrators' passwords are changed by their owners only.",
        "zh-CN": "管理员的密码只能由本人修改。",
    },
}

from app.web.messages_lab import LAB_MESSAGES  # noqa: E402

MESSAGES.update(LAB_MESSAGES)

from app.web.messages_api import API_MESSAGES  # noqa: E402

MESSAGES.update(API_MESSAGES)
