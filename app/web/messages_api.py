"""Messages of the REST API and the shared error model (en, zh-CN)."""

API_MESSAGES: dict[str, dict[str, str]] = {
    "error.not_authenticated": {"en": "Not authenticated.", "zh-CN": "未登录或未认证。"},
    "error.password_change": {
        "en": "Password change required.",
        "zh-CN": "请先修改密码。",
    },
    "api.not_authenticated": {
        "en": "Not authenticated.",
        "zh-CN": "未认证：请发送“Authorization: Bearer <令牌>”或先登录。",
    },
    "api.csrf_header": {
        "en": "Missing or wrong X-CSRF-Token header.",
        "zh-CN": "缺少 X-CSRF-Token 请求头，或其值不正确。",
    },
    "api.change_password_first": {
        "en": "This account must change its initial password in the browser first.",
        "zh-CN": "该账号须先在浏览器中修改初始密码。",
    },
    "api.rate_session": {
        "en": "Too many requests from this session; slow down.",
        "zh-CN": "该会话请求过于频繁，请放慢速度。",
    },
    "api.bad_token": {
        "en": "Invalid, revoked or expired token.",
        "zh-CN": "令牌无效、已撤销或已过期。",
    },
    "api.rate_token": {
        "en": "Too many requests with this token; slow down.",
        "zh-CN": "该令牌请求过于频繁，请放慢速度。",
    },
    "api.scope_missing": {
        "en": "This token lacks the '{scope}' scope.",
        "zh-CN": "该令牌没有“{scope}”权限范围。",
    },
    "api.teachers_only": {"en": "Only teachers may do this.", "zh-CN": "只有教师可以执行此操作。"},
    "api.teachers_or_admins_only": {
        "en": "Only teachers and administrators may do this.",
        "zh-CN": "只有教师和管理员可以执行此操作。",
    },
    "api.login_throttled": {
        "en": "Too many failed log-in attempts; wait and try again.",
        "zh-CN": "登录失败次数过多，请稍后再试。",
    },
    "api.login_busy": {
        "en": "The server is busy checking passwords; try again.",
        "zh-CN": "服务器正忙于校验密码，请重试。",
    },
    "api.bad_login": {"en": "Wrong username or password.", "zh-CN": "用户名或密码错误。"},
    "api.no_such_user": {"en": "No such user.", "zh-CN": "没有这个用户。"},
    "api.reset_not_yours": {
        "en": "You may reset only accounts your roster created and that no other teacher's "
        "course holds; ask an administrator.",
        "zh-CN": "你只能重置由你的名单创建、且不在其他教师课程中的账号；请联系管理员。",
    },
    "api.body_too_large": {
        "en": "The body is larger than {limit} bytes.",
        "zh-CN": "请求体超过 {limit} 字节。",
    },
    "api.bad_angle": {
        "en": "angle_deg must be a finite number of degrees.",
        "zh-CN": "angle_deg 必须是有限的度数。",
    },
    "api.content_type": {
        "en": "Send application/json or text/csv.",
        "zh-CN": "请以 application/json 或 text/csv 发送。",
    },
    "api.samples_not_finite": {
        "en": "Every sample must be a finite number.",
        "zh-CN": "每个读数都必须是有限的数。",
    },
    "api.times_count": {
        "en": "times_s must have one entry per sample.",
        "zh-CN": "times_s 必须与读数一一对应。",
    },
    "api.times_not_finite": {
        "en": "Every time must be a finite number.",
        "zh-CN": "每个时间都必须是有限的数。",
    },
    "api.station_or_assignment": {
        "en": "Give either station (practice) or assignment_id.",
        "zh-CN": "请给出 station（练习）或 assignment_id 之一。",
    },
    "json.out_of_range": {
        "en": "The number {number} is out of range.",
        "zh-CN": "数字 {number} 超出范围。",
    },
    "json.constant": {
        "en": "{name} is not a number JSON allows: send finite numbers only.",
        "zh-CN": "{name} 不是 JSON 允许的数：只能发送有限的数。",
    },
    "json.too_deep": {"en": "The JSON is nested too deeply.", "zh-CN": "JSON 嵌套层数过深。"},
    "json.invalid": {"en": "The body is not valid JSON.", "zh-CN": "请求体不是有效的 JSON。"},
    "lab.no_such_session": {"en": "No such session.", "zh-CN": "没有这个实验记录。"},
    "lab.no_such_assignment": {"en": "No such assignment.", "zh-CN": "没有这个作业。"},
    "lab.uploads_not_allowed": {
        "en": "This assignment does not allow uploaded readings.",
        "zh-CN": "该作业不允许上传读数。",
    },
    "lab.method_not_allowed": {
        "en": "This assignment does not allow that way of recording.",
        "zh-CN": "该作业不允许这种记录方式。",
    },
    "course.no_such_course": {"en": "No such course.", "zh-CN": "没有这门课程。"},
    "course.no_such_student": {
        "en": "No such student in this course.",
        "zh-CN": "本课程中没有这名学生。",
    },
    "review.no_such_assignment": {"en": "No such assignment.", "zh-CN": "没有这个作业。"},
    "review.no_such_session": {"en": "No such submission.", "zh-CN": "没有这份提交。"},
}
